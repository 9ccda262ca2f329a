#include "core/render/silhouette_feather.h"

#include <gtest/gtest.h>

#include <vector>

#include "core/base/error.h"

namespace lumistage {
namespace {

constexpr int kW = 9, kH = 8;

uint8_t* at(std::vector<uint8_t>& rgba, int x, int y) {
  return rgba.data() + 4 * (y * kW + x);
}

// A 4x3 block of opaque (200, 100, 50) at x 2..5, y 2..4, with a hole at (3, 3).
std::vector<uint8_t> block() {
  std::vector<uint8_t> rgba(kW * kH * 4, 0);
  for (int y = 2; y <= 4; ++y)
    for (int x = 2; x <= 5; ++x) {
      uint8_t* p = at(rgba, x, y);
      p[0] = 200, p[1] = 100, p[2] = 50, p[3] = 255;
    }
  at(rgba, 3, 3)[3] = 0, at(rgba, 3, 3)[0] = at(rgba, 3, 3)[1] = at(rgba, 3, 3)[2] = 0;
  return rgba;
}

TEST(SilhouetteFeather, EmptyPixelsBesideTheSilhouetteGetItsColourAtTheirOdds) {
  const std::vector<uint8_t> before = block();
  std::vector<uint8_t> rgba = before;
  featherSilhouette(rgba, kW, kH);
  // Opaque pixels are left as they were.
  for (int y = 2; y <= 4; ++y)
    for (int x = 2; x <= 5; ++x) {
      if (x == 3 && y == 3) continue;  // the hole
      EXPECT_EQ(at(rgba, x, y)[3], 255);
    }
  // Beside a straight edge (3 opaque neighbours): 20/255, premultiplied.
  EXPECT_EQ(at(rgba, 3, 1)[3], 20);
  EXPECT_EQ(at(rgba, 3, 1)[0], (200 * 20 + 127) / 255);
  EXPECT_EQ(at(rgba, 3, 1)[1], (100 * 20 + 127) / 255);
  EXPECT_EQ(at(rgba, 6, 3)[3], 20);
  // Off a convex corner (1 opaque neighbour): 4/255.
  EXPECT_EQ(at(rgba, 1, 1)[3], 4);
  EXPECT_EQ(at(rgba, 6, 5)[3], 4);
  // Beside the edge's last pixel (2): 8/255.
  EXPECT_EQ(at(rgba, 2, 1)[3], 8);
  // The hole (8 opaque neighbours) is filled: 254/255 (never opaque), the colour's.
  EXPECT_EQ(at(rgba, 3, 3)[3], 254);
  EXPECT_EQ(at(rgba, 3, 3)[0], (200 * 254 + 127) / 255);
  // Two pixels away: untouched.
  EXPECT_EQ(at(rgba, 0, 0)[3], 0);
  EXPECT_EQ(at(rgba, 7, 3)[3], 0);
  EXPECT_EQ(at(rgba, 3, 6)[0], 0);
  // Nothing the feather writes is opaque, so a second pass changes nothing.
  std::vector<uint8_t> again = rgba;
  featherSilhouette(again, kW, kH);
  EXPECT_EQ(again, rgba);
}

TEST(SilhouetteFeather, RowSpansWalkOnlyWhatTheyBoundAndGiveTheSame) {
  std::vector<uint8_t> whole = block(), spanned = block();
  featherSilhouette(whole, kW, kH);
  std::vector<int> begin(kH, kW), end(kH, 0);
  for (int y = 2; y <= 4; ++y) begin[y] = 2, end[y] = 6;
  featherSilhouette(spanned, kW, kH, begin, end);
  EXPECT_EQ(spanned, whole);
  // A wrong size names what it wanted.
  EXPECT_THROW(featherSilhouette(spanned, kW, kH + 1), Error);
  EXPECT_THROW(featherSilhouette(spanned, kW, kH, std::vector<int>(2), std::vector<int>(2)), Error);
}

TEST(SilhouetteFeather, SingleProcessViewsAreShownOpaqueThenFeathered) {
  std::vector<uint8_t> rgba = block(), shown = block();
  at(rgba, 4, 3)[3] = 16;  // a rim pixel at a sixteenth of the cameras' weight
  finishSingleProcessView(rgba, kW, kH);
  featherSilhouette(shown, kW, kH);
  EXPECT_EQ(rgba, shown);
}

}  // namespace
}  // namespace lumistage
