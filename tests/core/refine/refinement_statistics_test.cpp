// The node's statistics: exact combination and the compact wire form.
#include "core/refine/refinement_statistics.h"

#include <gtest/gtest.h>

#include <random>

namespace lumistage {
namespace {

RefinementStatistics randomStatistics(std::mt19937& rng, int vertices, int offsets, int cameras) {
  RefinementStatistics s;
  s.reset(vertices, offsets, 6);
  std::uniform_int_distribution<int> count(0, cameras), colour(0, 63), coin(0, 3);
  for (int i = 0; i < s.sampleCount(); ++i) {
    if (coin(rng) == 0) {
      s.outside[i] = uint8_t(1 + count(rng) % cameras);
      continue;
    }
    const int n = count(rng);
    s.colour_count[i] = uint8_t(n);
    for (int k = 0; k < n; ++k) {
      for (int ch = 0; ch < 3; ++ch) {
        const uint32_t c = uint32_t(colour(rng));
        s.sums[3 * i + ch] = uint16_t(s.sums[3 * i + ch] + c);
        s.squares[i] += c * c;
      }
    }
  }
  return s;
}

TEST(RefinementStatistics, WireFormRoundTripsExactly) {
  std::mt19937 rng(7);
  for (int cameras : {1, 3, 8}) {
    const RefinementStatistics s = randomStatistics(rng, 300, 21, cameras);
    std::vector<uint8_t> wire;
    encodeRefinementStatistics(s, wire);
    RefinementStatistics back;
    std::string error;
    ASSERT_TRUE(decodeRefinementStatistics(wire, back, &error)) << error;
    EXPECT_TRUE(back == s) << cameras << " cameras";
    // Compact: well under the 18 bytes a sample of plain 16-bit sums and 32-bit squares.
    EXPECT_LT(wire.size(), size_t(s.sampleCount()) * (cameras <= 3 ? 5 : 7));
  }
}

TEST(RefinementStatistics, MalformedWireIsRefused) {
  std::mt19937 rng(8);
  const RefinementStatistics s = randomStatistics(rng, 50, 21, 3);
  std::vector<uint8_t> wire;
  encodeRefinementStatistics(s, wire);
  RefinementStatistics back;
  std::string error;
  for (size_t cut : {size_t(0), size_t(5), wire.size() / 2, wire.size() - 1}) {
    EXPECT_FALSE(decodeRefinementStatistics(std::span(wire.data(), cut), back, &error)) << cut;
    EXPECT_FALSE(error.empty());
  }
  std::vector<uint8_t> bad = wire;
  bad[5] = 9;  // colour bits
  EXPECT_FALSE(decodeRefinementStatistics(bad, back));
  bad = wire;
  bad[0] = 0xff, bad[1] = 0xff, bad[2] = 0xff;  // absurd vertex count
  EXPECT_FALSE(decodeRefinementStatistics(bad, back));
}

TEST(RefinementStatistics, CombiningIsExactAndOrderIndependent) {
  std::mt19937 rng(9);
  std::vector<RefinementStatistics> nodes;
  for (int n = 0; n < 4; ++n) nodes.push_back(randomStatistics(rng, 200, 21, 3));
  RefinementStatistics forward, backward;
  forward.reset(200, 21, 6);
  backward.reset(200, 21, 6);
  for (int n = 0; n < 4; ++n) ASSERT_TRUE(forward.add(nodes[n]));
  for (int n = 3; n >= 0; --n) ASSERT_TRUE(backward.add(nodes[n]));
  EXPECT_TRUE(forward == backward);
  // Sums are the plain sums where no node saw the sample outside; nothing where one did.
  for (int i = 0; i < forward.sampleCount(); ++i) {
    int outside = 0, count = 0;
    uint32_t squares = 0;
    for (const auto& n : nodes)
      outside += n.outside[i], count += n.colour_count[i], squares += n.squares[i];
    EXPECT_EQ(forward.outside[i], outside);
    EXPECT_EQ(forward.colour_count[i], outside ? 0 : count);
    EXPECT_EQ(forward.squares[i], outside ? 0 : squares);
  }
  RefinementStatistics other;
  other.reset(201, 21, 6);
  EXPECT_FALSE(forward.add(other));
}

}  // namespace
}  // namespace lumistage
