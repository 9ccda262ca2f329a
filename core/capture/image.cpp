#include "core/capture/image.h"

namespace lumistage {

const char* pixelFormatName(PixelFormat format) {
  switch (format) {
    case PixelFormat::kMono8:
      return "mono8";
    case PixelFormat::kBayerRggb8:
      return "bayer_rggb8";
    case PixelFormat::kRgb8:
      return "rgb8";
  }
  return "?";
}

std::optional<PixelFormat> parsePixelFormat(std::string_view name) {
  for (PixelFormat f : {PixelFormat::kMono8, PixelFormat::kBayerRggb8, PixelFormat::kRgb8}) {
    if (name == pixelFormatName(f)) return f;
  }
  return std::nullopt;
}

int bytesPerPixel(PixelFormat format) {
  return format == PixelFormat::kRgb8 ? 3 : 1;
}

void rgbaToBayerRggb(const uint8_t* rgba, int width, int height, uint8_t* bayer) {
  for (int y = 0; y < height; ++y) {
    const uint8_t* row = rgba + size_t(y) * width * 4;
    uint8_t* out = bayer + size_t(y) * width;
    // Channel: R at (even, even), B at (odd, odd), G elsewhere.
    const int even = (y & 1) ? 1 : 0, odd = (y & 1) ? 2 : 1;
    for (int x = 0; x < width; x += 2) out[x] = row[4 * x + even];
    for (int x = 1; x < width; x += 2) out[x] = row[4 * x + odd];
  }
}

void rgbaToRgb(const uint8_t* rgba, int width, int height, uint8_t* rgb) {
  const size_t n = size_t(width) * height;
  for (size_t p = 0; p < n; ++p) {
    rgb[3 * p] = rgba[4 * p];
    rgb[3 * p + 1] = rgba[4 * p + 1];
    rgb[3 * p + 2] = rgba[4 * p + 2];
  }
}

void rgbaToImage(const uint8_t* rgba, int width, int height, PixelFormat format, Image& out) {
  out.resize(format, width, height);
  switch (format) {
    case PixelFormat::kBayerRggb8:
      rgbaToBayerRggb(rgba, width, height, out.pixels.data());
      break;
    case PixelFormat::kRgb8:
      rgbaToRgb(rgba, width, height, out.pixels.data());
      break;
    case PixelFormat::kMono8:
      for (size_t p = 0; p < size_t(width) * height; ++p) {
        out.pixels[p] =
            uint8_t((77 * rgba[4 * p] + 150 * rgba[4 * p + 1] + 29 * rgba[4 * p + 2]) >> 8);
      }
      break;
  }
}

}  // namespace lumistage
