#include "core/capture/image.h"

#include <bit>
#include <cstring>
#include <opencv2/imgproc.hpp>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

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

namespace {

template <int kRedX>
void cellRow(const uint8_t* red_row, const uint8_t* blue_row, int cells, uint8_t* out) {
  int x = 0;
#if defined(__SSE2__)
  // Eight cells at a time: 16-bit lanes hold a cell's two bytes of each row.
  const __m128i low = _mm_set1_epi16(0x00ff), opaque = _mm_set1_epi16(int16_t(0xff00));
  for (; x + 8 <= cells; x += 8) {
    const __m128i r_row = _mm_loadu_si128(reinterpret_cast<const __m128i*>(red_row + 2 * x));
    const __m128i b_row = _mm_loadu_si128(reinterpret_cast<const __m128i*>(blue_row + 2 * x));
    const __m128i r_even = _mm_and_si128(r_row, low), r_odd = _mm_srli_epi16(r_row, 8);
    const __m128i b_even = _mm_and_si128(b_row, low), b_odd = _mm_srli_epi16(b_row, 8);
    const __m128i r = kRedX == 0 ? r_even : r_odd, g1 = kRedX == 0 ? r_odd : r_even;
    const __m128i g2 = kRedX == 0 ? b_even : b_odd, b = kRedX == 0 ? b_odd : b_even;
    const __m128i g = _mm_avg_epu16(g1, g2);  // (g1 + g2 + 1) >> 1
    const __m128i rg = _mm_or_si128(r, _mm_slli_epi16(g, 8)), ba = _mm_or_si128(b, opaque);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + 4 * x), _mm_unpacklo_epi16(rg, ba));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + 4 * x + 16), _mm_unpackhi_epi16(rg, ba));
  }
#endif
  for (; x < cells; ++x) {
    const uint8_t* r = red_row + 2 * x;
    const uint8_t* b = blue_row + 2 * x;
    out[4 * x] = r[kRedX];
    out[4 * x + 1] = uint8_t((unsigned(r[1 - kRedX]) + b[kRedX] + 1) >> 1);
    out[4 * x + 2] = b[1 - kRedX];
    out[4 * x + 3] = 255;
  }
}

}  // namespace

void bayerCellsToRgba(const ImageView& image, uint8_t* rgba) {
  const BayerLayout layout = bayerLayout(image.format);
  const int cells_x = image.width / 2, cells_y = image.height / 2;
  for (int y = 0; y < cells_y; ++y) {
    const uint8_t* top = image.data + size_t(2 * y) * image.width;
    const uint8_t* bottom = top + image.width;
    const uint8_t* red_row = layout.red_y == 0 ? top : bottom;
    const uint8_t* blue_row = layout.red_y == 0 ? bottom : top;
    uint8_t* out = rgba + size_t(y) * cells_x * 4;
    if (layout.red_x == 0) {
      cellRow<0>(red_row, blue_row, cells_x, out);
    } else {
      cellRow<1>(red_row, blue_row, cells_x, out);
    }
  }
}

void demosaicBayerToRgba(const ImageView& image, uint8_t* rgba) {
  // OpenCV names a pattern by its second row: its "BG" is RGGB.
  const BayerLayout l = bayerLayout(image.format);
  const int code = l.red_y == 0 ? (l.red_x == 0 ? cv::COLOR_BayerBG2RGBA : cv::COLOR_BayerGB2RGBA)
                                : (l.red_x == 0 ? cv::COLOR_BayerGR2RGBA : cv::COLOR_BayerRG2RGBA);
  const cv::Mat bayer(image.height, image.width, CV_8UC1, const_cast<uint8_t*>(image.data));
  cv::Mat out(image.height, image.width, CV_8UC4, rgba);
  cv::cvtColor(bayer, out, code);
}

void rgbaToRgb(const uint8_t* rgba, int width, int height, uint8_t* rgb) {
  const size_t n = size_t(width) * height;
  for (size_t p = 0; p < n; ++p) {
    rgb[3 * p] = rgba[4 * p];
    rgb[3 * p + 1] = rgba[4 * p + 1];
    rgb[3 * p + 2] = rgba[4 * p + 2];
  }
}

void rgbToRgba(const uint8_t* rgb, size_t pixels, uint8_t* rgba) {
  static_assert(std::endian::native == std::endian::little, "a pixel's 4th byte is the word's top");
  // A pixel a 32-bit word: its 3 bytes and the next pixel's first, which the alpha replaces (the
  // last pixel, which has no next, byte by byte): about twice the byte loop's speed.
  size_t p = 0;
  for (; p + 1 < pixels; ++p) {
    uint32_t word;
    std::memcpy(&word, rgb + 3 * p, 4);
    word |= 0xff000000u;
    std::memcpy(rgba + 4 * p, &word, 4);
  }
  for (; p < pixels; ++p) {
    rgba[4 * p] = rgb[3 * p];
    rgba[4 * p + 1] = rgb[3 * p + 1];
    rgba[4 * p + 2] = rgb[3 * p + 2];
    rgba[4 * p + 3] = 255;
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
