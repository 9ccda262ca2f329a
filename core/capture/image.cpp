#include "core/capture/image.h"

namespace lumistage {

const char* pixelFormatName(PixelFormat format) {
  switch (format) {
    case PixelFormat::kMono8:
      return "mono8";
    case PixelFormat::kBayerRggb8:
      return "bayer_rggb8";
    case PixelFormat::kBayerGrbg8:
      return "bayer_grbg8";
    case PixelFormat::kBayerGbrg8:
      return "bayer_gbrg8";
    case PixelFormat::kBayerBggr8:
      return "bayer_bggr8";
    case PixelFormat::kRgb8:
      return "rgb8";
  }
  return "?";
}

std::optional<PixelFormat> parsePixelFormat(std::string_view name) {
  for (PixelFormat f : kAllPixelFormats) {
    if (name == pixelFormatName(f)) return f;
  }
  return std::nullopt;
}

std::string pixelFormatNames() {
  std::string names;
  for (PixelFormat f : kAllPixelFormats)
    names += (names.empty() ? "" : ", ") + std::string(pixelFormatName(f));
  return names;
}

int bytesPerPixel(PixelFormat format) {
  return format == PixelFormat::kRgb8 ? 3 : 1;
}

bool isBayer(PixelFormat format) {
  return format != PixelFormat::kMono8 && format != PixelFormat::kRgb8;
}

void rgbaToBayer(const uint8_t* rgba, int width, int height, BayerLayout layout, uint8_t* bayer) {
  for (int y = 0; y < height; ++y) {
    const uint8_t* row = rgba + size_t(y) * width * 4;
    uint8_t* out = bayer + size_t(y) * width;
    // On a row that holds R: R at red_x, G between; on the other: G at red_x, B between.
    const bool red_row = (y & 1) == layout.red_y;
    const int at_red_x = red_row ? 0 : 1, other = red_row ? 1 : 2;
    for (int x = 0; x < width; ++x)
      out[x] = row[4 * x + (((x & 1) == layout.red_x) ? at_red_x : other)];
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
    case PixelFormat::kBayerGrbg8:
    case PixelFormat::kBayerGbrg8:
    case PixelFormat::kBayerBggr8:
      rgbaToBayer(rgba, width, height, bayerLayout(format), out.pixels.data());
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
