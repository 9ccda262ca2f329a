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

}  // namespace
}  // namespace lumistage
