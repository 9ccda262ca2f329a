#pragma once

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace lumistage {

// Pixel layouts of camera images. Bayer is what most GigE Vision colour cameras deliver: one byte
// a pixel, rows R G R G... / G B G B... (RGGB); it is also the cheapest to upload and to store.
enum class PixelFormat : uint8_t { kMono8, kBayerRggb8, kRgb8 };

const char* pixelFormatName(PixelFormat format);  // "mono8", "bayer_rggb8", "rgb8"
std::optional<PixelFormat> parsePixelFormat(std::string_view name);
int bytesPerPixel(PixelFormat format);

// A view of tightly packed pixels owned elsewhere.
struct ImageView {
  PixelFormat format = PixelFormat::kMono8;
  int width = 0;
  int height = 0;
  const uint8_t* data = nullptr;

  size_t bytes() const { return size_t(width) * height * bytesPerPixel(format); }
};

// An image that owns its pixels. Reused from frame to frame: resize() keeps the allocation when
// the size does not grow.
struct Image {
  PixelFormat format = PixelFormat::kMono8;
  int width = 0;
  int height = 0;
  std::vector<uint8_t> pixels;

  void resize(PixelFormat f, int w, int h) {
    format = f, width = w, height = h;
    pixels.resize(size_t(w) * h * bytesPerPixel(f));
  }
  ImageView view() const { return {format, width, height, pixels.data()}; }
};

// From the renderer's RGBA8 (rows top first) to what a camera would deliver.
void rgbaToBayerRggb(const uint8_t* rgba, int width, int height, uint8_t* bayer);
void rgbaToRgb(const uint8_t* rgba, int width, int height, uint8_t* rgb);
void rgbaToImage(const uint8_t* rgba, int width, int height, PixelFormat format, Image& out);

}  // namespace lumistage
