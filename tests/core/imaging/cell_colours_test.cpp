// The actor's colours at the silhouette's cells (core/imaging/cell_colours.h): what a node sends
// with its silhouettes for motion capture's arms.
#include "core/imaging/cell_colours.h"

#include <gtest/gtest.h>

namespace lumistage {
namespace {

// A 16x8 image in two halves, red on the left and blue on the right, as RGB8 and as each Bayer
// layout; its silhouette at step 4 holds three cells (0,0), (3,0) and (2,1).
Image twoColours(PixelFormat format) {
  std::vector<uint8_t> rgba(16 * 8 * 4);
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 16; ++x) {
      uint8_t* p = rgba.data() + 4 * (y * 16 + x);
      p[0] = x < 8 ? 200 : 20, p[1] = x < 8 ? 40 : 60, p[2] = x < 8 ? 10 : 180, p[3] = 255;
    }
  }
  Image image;
  rgbaToImage(rgba.data(), 16, 8, format, image);
  return image;
}

LowResSilhouette threeCells() {
  LowResSilhouette s;
  s.reset(2, 4, 16, 8);
  s.set(0, 0);
  s.set(3, 0);
  s.set(2, 1);
  return s;
}

TEST(CellColours, EachCellOfTheActorHasItsMeanColourInEveryPixelFormat) {
  const LowResSilhouette s = threeCells();
  for (PixelFormat format : {PixelFormat::kRgb8, PixelFormat::kBayerRggb8, PixelFormat::kBayerGrbg8,
                             PixelFormat::kBayerGbrg8, PixelFormat::kBayerBggr8}) {
    std::vector<uint8_t> packed;
    sampleSilhouetteColours(twoColours(format).view(), s, packed);
    // In the bits' order: (0,0) red, (3,0) blue, (2,1) blue.
    EXPECT_EQ(packed, (std::vector<uint8_t>{200, 40, 10, 20, 60, 180, 20, 60, 180})) << int(format);
    CellColours dense;
    ASSERT_TRUE(expandSilhouetteColours(s, packed.data(), packed.size(), dense));
    EXPECT_EQ(dense.camera, 2);
    EXPECT_EQ(dense.width, 4);
    EXPECT_EQ(dense.at(0, 0)[0], 200);
    EXPECT_EQ(dense.at(2, 1)[2], 180);
    EXPECT_EQ(dense.at(1, 0)[0], 0);  // not the actor
  }
}

TEST(CellColours, ColoursOfAnotherCountAreRefused) {
  const LowResSilhouette s = threeCells();
  const std::vector<uint8_t> packed(6, 9);  // two cells' worth for three cells
  CellColours dense;
  EXPECT_FALSE(expandSilhouetteColours(s, packed.data(), packed.size(), dense));
  EXPECT_TRUE(dense.rgb.empty());
  // A sender's bits past the last cell are no cells: still three, and nine bytes fit.
  LowResSilhouette padded;
  padded.reset(0, 4, 12, 12);  // 3x3 cells: 9 bits in 2 bytes
  padded.set(0, 0);
  padded.bits[1] |= 0xfe;  // bits 9-15: padding
  const std::vector<uint8_t> one(3, 5);
  EXPECT_TRUE(expandSilhouetteColours(padded, one.data(), one.size(), dense));
  EXPECT_EQ(dense.at(0, 0)[1], 5);
}

}  // namespace
}  // namespace lumistage
