#include "core/capture/image.h"

#include <gtest/gtest.h>

#include "core/imaging/keyer.h"

namespace lumistage {
namespace {

TEST(Image, EveryBayerLayoutMosaicsAndReadsBackTheColour) {
  // A flat colour mosaicked in any layout reads back as that colour at every pixel.
  std::vector<uint8_t> rgba(6 * 4 * 4);
  for (size_t p = 0; p < rgba.size(); p += 4)
    rgba[p] = 200, rgba[p + 1] = 90, rgba[p + 2] = 30, rgba[p + 3] = 255;
  for (PixelFormat format : kAllPixelFormats) {
    Image image;
    rgbaToImage(rgba.data(), 6, 4, format, image);
    ASSERT_EQ(image.pixels.size(), size_t(6 * 4 * bytesPerPixel(format)));
    for (int y = 0; y < 4; ++y) {
      for (int x = 0; x < 6; ++x) {
        const Rgb c = colourAt(image.view(), x, y);
        if (format == PixelFormat::kMono8) {
          EXPECT_EQ(c.r, c.g);
        } else {
          EXPECT_EQ(c.r, 200) << pixelFormatName(format) << " at " << x << "," << y;
          EXPECT_EQ(c.g, 90) << pixelFormatName(format);
          EXPECT_EQ(c.b, 30) << pixelFormatName(format);
        }
      }
    }
  }
}

TEST(Image, RgbWidensToRgbaWithOpaqueAlpha) {
  for (size_t pixels : {size_t(0), size_t(1), size_t(2), size_t(257)}) {
    std::vector<uint8_t> rgb(3 * pixels);
    for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = uint8_t(i * 37 + 11);
    // One byte more than the pixels need, which the conversion must leave alone.
    std::vector<uint8_t> rgba(4 * pixels + 1, 7);
    rgbToRgba(rgb.data(), pixels, rgba.data());
    for (size_t p = 0; p < pixels; ++p) {
      for (int c = 0; c < 3; ++c) EXPECT_EQ(rgba[4 * p + c], rgb[3 * p + c]) << p << " " << c;
      EXPECT_EQ(rgba[4 * p + 3], 255) << p;
    }
    EXPECT_EQ(rgba.back(), 7);
  }
}

TEST(Image, BayerLayoutsPutRedWhereTheirNamesSay) {
  // R=1, G=2, B=3 everywhere: the first cell reads as the name's first two rows.
  std::vector<uint8_t> rgba(2 * 2 * 4);
  for (size_t p = 0; p < rgba.size(); p += 4) rgba[p] = 1, rgba[p + 1] = 2, rgba[p + 2] = 3;
  const std::pair<PixelFormat, std::array<uint8_t, 4>> expected[] = {
      {PixelFormat::kBayerRggb8, {1, 2, 2, 3}},
      {PixelFormat::kBayerGrbg8, {2, 1, 3, 2}},
      {PixelFormat::kBayerGbrg8, {2, 3, 1, 2}},
      {PixelFormat::kBayerBggr8, {3, 2, 2, 1}}};
  for (const auto& [format, cell] : expected) {
    Image image;
    rgbaToImage(rgba.data(), 2, 2, format, image);
    EXPECT_EQ(image.pixels, std::vector<uint8_t>(cell.begin(), cell.end()))
        << pixelFormatName(format);
    EXPECT_TRUE(isBayer(format));
    EXPECT_EQ(parsePixelFormat(pixelFormatName(format)), format);
  }
  EXPECT_FALSE(parsePixelFormat("bayer_rgbg8"));
}

TEST(Image, DemosaicRecoversColoursThatVaryLinearlyInsideTheBorder) {
  // Each channel a different linear ramp (even steps, so that every bilinear mean is exact):
  // mosaicked in any layout, the demosaic gives every pixel's colour back inside the border, and
  // within a diagonal pixel's step on it; the 2x2 cells are off inside too.
  const int width = 12, height = 8;
  std::vector<uint8_t> rgba(width * height * 4);
  auto colour = [](int x, int y, int c) {
    return c == 0 ? 20 + 8 * x + 2 * y : (c == 1 ? 200 - 6 * y + 2 * x : 40 + 4 * x + 10 * y);
  };
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 4; ++c)
        rgba[4 * (y * width + x) + c] = uint8_t(c == 3 ? 255 : colour(x, y, c));
  for (PixelFormat format : kAllPixelFormats) {
    if (!isBayer(format)) continue;
    Image image;
    rgbaToImage(rgba.data(), width, height, format, image);
    std::vector<uint8_t> out(rgba.size(), 7);
    demosaicBayerToRgba(image.view(), out.data());
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        const bool border = x == 0 || y == 0 || x == width - 1 || y == height - 1;
        for (int c = 0; c < 4; ++c) {
          const int i = 4 * (y * width + x) + c;
          EXPECT_NEAR(out[i], rgba[i], border ? 14 : 0)  // 14: blue's diagonal step
              << pixelFormatName(format) << " at " << x << "," << y << " channel " << c;
        }
      }
    }
    std::vector<uint8_t> cells(width / 2 * height / 2 * 4);
    bayerCellsToRgba(image.view(), cells.data());
    EXPECT_NE(cells[1], rgba[1]) << pixelFormatName(format);  // not what the cells give
  }
}

TEST(Image, BayerCellsAreTheirRedTheMeanOfTheirGreensAndTheirBlue) {
  // An image of odd width and height (its last column and row belong to no cell) whose 18 cells
  // a row take the eight-at-a-time path and the cell-at-a-time tail: every cell against the
  // colour its four pixels say, in every layout (mono8 read as the default one).
  const int width = 37, height = 9, cells_x = width / 2, cells_y = height / 2;
  std::vector<uint8_t> pixels(width * height);
  for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = uint8_t((i * 97 + 13) % 256);
  for (PixelFormat format : kAllPixelFormats) {
    if (format == PixelFormat::kRgb8) continue;
    const BayerLayout layout = bayerLayout(format);
    std::vector<uint8_t> rgba(cells_x * cells_y * 4, 7);
    bayerCellsToRgba({format, width, height, pixels.data()}, rgba.data());
    for (int cy = 0; cy < cells_y; ++cy) {
      for (int cx = 0; cx < cells_x; ++cx) {
        auto at = [&](int dx, int dy) { return int(pixels[(2 * cy + dy) * width + 2 * cx + dx]); };
        const int r = at(layout.red_x, layout.red_y), b = at(1 - layout.red_x, 1 - layout.red_y);
        const int g =
            (at(1 - layout.red_x, layout.red_y) + at(layout.red_x, 1 - layout.red_y) + 1) / 2;
        const uint8_t* texel = &rgba[4 * (cy * cells_x + cx)];
        EXPECT_EQ(texel[0], r) << pixelFormatName(format) << " cell " << cx << "," << cy;
        EXPECT_EQ(texel[1], g) << pixelFormatName(format) << " cell " << cx << "," << cy;
        EXPECT_EQ(texel[2], b) << pixelFormatName(format) << " cell " << cx << "," << cy;
        EXPECT_EQ(texel[3], 255);
      }
    }
  }
}

}  // namespace
}  // namespace lumistage
