#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace lumistage {

// Pixel layouts of camera images. Bayer is what most GigE Vision colour cameras deliver: one byte
// a pixel, a 2x2 cell of R, two G and B repeated; it is also the cheapest to upload and to store.
// The four Bayer formats differ in where R sits in the cell: RGGB (top left), GRBG (top right),
// GBRG (bottom left), BGGR (bottom right), named by the cell's first two rows as GenICam does.
enum class PixelFormat : uint8_t {
  kMono8,
  kBayerRggb8,
  kRgb8,
  kBayerGrbg8,
  kBayerGbrg8,
  kBayerBggr8
};

inline constexpr PixelFormat kAllPixelFormats[] = {
    PixelFormat::kMono8,      PixelFormat::kBayerRggb8, PixelFormat::kBayerGrbg8,
    PixelFormat::kBayerGbrg8, PixelFormat::kBayerBggr8, PixelFormat::kRgb8};

// "mono8", "bayer_rggb8", "bayer_grbg8", "bayer_gbrg8", "bayer_bggr8", "rgb8"
const char* pixelFormatName(PixelFormat format);
std::optional<PixelFormat> parsePixelFormat(std::string_view name);
// "mono8, bayer_rggb8, ..., rgb8": for messages that say what was expected.
std::string pixelFormatNames();
int bytesPerPixel(PixelFormat format);
bool isBayer(PixelFormat format);
// Where R sits in a Bayer format's 2x2 cell (B is diagonally opposite, G in the other two).
struct BayerLayout {
  int red_x = 0, red_y = 0;
};
// Inline: the keyer asks for it at every pixel it reads.
inline BayerLayout bayerLayout(PixelFormat format) {
  switch (format) {
    case PixelFormat::kBayerGrbg8:
      return {1, 0};
    case PixelFormat::kBayerGbrg8:
      return {0, 1};
    case PixelFormat::kBayerBggr8:
      return {1, 1};
    default:
      return {0, 0};
  }
}

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
void rgbaToBayer(const uint8_t* rgba, int width, int height, BayerLayout layout, uint8_t* bayer);
void rgbaToRgb(const uint8_t* rgba, int width, int height, uint8_t* rgb);
// RGB8 widened to RGBA8 (alpha 255), as GPUs take it: `pixels` of them.
void rgbToRgba(const uint8_t* rgb, size_t pixels, uint8_t* rgba);
void rgbaToImage(const uint8_t* rgba, int width, int height, PixelFormat format, Image& out);

// A Bayer image's 2x2 cells as RGBA8 (R, the mean of the two G rounded, B, 255), rows top first:
// (width / 2) x (height / 2) texels. Mono8 is read as a Bayer image of the default layout.
void bayerCellsToRgba(const ImageView& image, uint8_t* rgba);
// A Bayer image demosaiced at full resolution, RGBA8 (alpha 255), rows top first: each pixel's
// missing channels the mean of the pixels of that colour among its 8 neighbours (OpenCV's
// bilinear demosaic: exact inside the border for colours that vary linearly). For what must look
// like the camera's image, not for the hot paths. Mono8 is read as the default layout.
void demosaicBayerToRgba(const ImageView& image, uint8_t* rgba);

}  // namespace lumistage
