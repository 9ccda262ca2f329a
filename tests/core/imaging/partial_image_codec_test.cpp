#include "core/imaging/partial_image_codec.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <span>
#include <vector>

namespace lumistage {
namespace {

TEST(PartialImageCodec, RoundTripsExactly) {
  std::vector<uint8_t> rgba(64 * 48 * 4, 0), encoded, decoded;
  uint32_t state = 1;
  for (int y = 10; y < 30; ++y)
    for (int x = 5 + y % 7; x < 40; ++x)
      for (int k = 0; k < 4; ++k) {
        state = state * 1664525u + 1013904223u;
        rgba[4 * (y * 64 + x) + k] = uint8_t(state >> 24);  // some pixels all zero by chance
      }
  rgba[4 * 1000] = 0, rgba[4 * 1000 + 3] = 7;  // alpha alone
  for (const std::vector<uint8_t>& image :
       {rgba, std::vector<uint8_t>(rgba.size(), 0), std::vector<uint8_t>(rgba.size(), 9)}) {
    encodeAlphaRuns(image, encoded);
    ASSERT_TRUE(decodeAlphaRuns(encoded, image.size() / 4, decoded));
    EXPECT_EQ(decoded, image);
  }
  encodeAlphaRuns(rgba, encoded);
  EXPECT_LT(encoded.size(), rgba.size() / 2);
  EXPECT_FALSE(decodeAlphaRuns(std::span(encoded).first(encoded.size() - 1), 64 * 48, decoded));
  EXPECT_FALSE(decodeAlphaRuns(encoded, 64 * 48 - 1, decoded));
  EXPECT_FALSE(decodeAlphaRuns(encoded, 64 * 48 + 1, decoded));
}

TEST(PartialImageCodec, RleRoundTripAndBadRuns) {
  std::vector<uint8_t> rgba(300 * 4, 7);
  rgba[4 * 299] = 1;
  const std::vector<uint8_t> rle = encodeRleRgba(rgba);
  EXPECT_EQ(rle.size(), 3u * 5u);  // 256 + 43 equal pixels, then one other
  EXPECT_EQ(decodeRleRgba(rle, 300), rgba);
  EXPECT_TRUE(decodeRleRgba(rle, 299).empty());
  EXPECT_TRUE(decodeRleRgba(std::span(rle).first(7), 300).empty());
}

}  // namespace
}  // namespace lumistage
