// The node's statistics: exact combination and the wire form, packed and compressed.
#include "core/refine/refinement_statistics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

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
  // Edges where the hull leaves, some not located (0).
  std::uniform_int_distribution<int> edge(0, 255);
  for (int i = 0; i < s.sampleCount(); ++i)
    if (s.leavesHull(i)) s.edges[i] = uint8_t(edge(rng));
  // A point in four on a camera's contour.
  for (int v = 0; v < vertices; ++v) s.contour[v] = coin(rng) == 0;
  return s;
}

TEST(RefinementStatistics, WireFormRoundTripsExactly) {
  std::mt19937 rng(7);
  for (int cameras : {1, 3, 8}) {
    const RefinementStatistics s = randomStatistics(rng, 300, 21, cameras);
    std::vector<uint8_t> wire;
    encodeRefinementStatistics(s, wire);
    RefinementStatistics back;
    ASSERT_EQ(decodeRefinementStatistics(wire, back).error(), "");
    EXPECT_TRUE(back == s) << cameras << " cameras";
    // Compact: well under the 18 bytes a sample of plain 16-bit sums and 32-bit squares.
    EXPECT_LT(wire.size(), size_t(s.sampleCount()) * (cameras <= 3 ? 5 : 7));
  }
}

// The packed values are differences along the samples and the cameras' disagreement: where every
// camera sees a vertex's colour alike at every offset, they are zero but at each vertex's first
// sample, which is what makes a node's statistics compress (a third less than the sums as they
// are). And they round-trip as exactly as any others.
TEST(RefinementStatistics, PackedValuesAreDifferencesAndDisagreement) {
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> colour(0, 63);
  constexpr int kVertices = 100, kOffsets = 21, kCameras = 3;
  RefinementStatistics s;
  s.reset(kVertices, kOffsets, 6);
  for (int v = 0; v < kVertices; ++v) {
    const int rgb[3] = {colour(rng), colour(rng), colour(rng)};
    for (int t = 0; t < kOffsets; ++t) {
      const int i = v * kOffsets + t;
      s.colour_count[i] = kCameras;
      for (int c = 0; c < 3; ++c) {
        s.sums[3 * i + c] = uint16_t(kCameras * rgb[c]);
        s.squares[i] += uint32_t(kCameras * rgb[c] * rgb[c]);
      }
    }
  }
  std::vector<uint8_t> packed;
  encodeRefinementStatistics(s, packed);
  const size_t n = size_t(s.sampleCount());
  // 1-byte values, then the contour bits (none set).
  ASSERT_EQ(packed.size(), kPackedStatisticsHeaderBytes + n + 3 * n + n + contourBytes(kVertices));
  const size_t values = packed.size() - kPackedStatisticsHeaderBytes - n;
  const size_t zeros = size_t(std::count(packed.end() - values, packed.end(), uint8_t(0)));
  EXPECT_GE(zeros, values - 3 * kVertices);  // each vertex's first sums may differ
  RefinementStatistics back;
  ASSERT_EQ(decodeRefinementStatistics(packed, back).error(), "");
  EXPECT_TRUE(back == s);
  // One camera's red one level higher at one sample: its residual is no longer zero (and the red
  // differences there and after it), and the values still round-trip.
  s.sums[3 * 5] = uint16_t(s.sums[3 * 5] + 1);
  s.squares[5] += 2 * uint32_t(s.sums[3 * 5] - 1) / kCameras + 1;  // (r + 1)² - r²
  encodeRefinementStatistics(s, packed);
  const size_t residual = kPackedStatisticsHeaderBytes + n + 3 * n + 5;
  EXPECT_NE(packed[residual], 0);
  EXPECT_EQ(packed[residual - 1], 0);
  EXPECT_EQ(size_t(std::count(packed.end() - values, packed.end(), uint8_t(0))), zeros - 3);
  ASSERT_EQ(decodeRefinementStatistics(packed, back).error(), "");
  EXPECT_TRUE(back == s);
}

TEST(RefinementStatistics, MalformedWireIsRefused) {
  std::mt19937 rng(8);
  const RefinementStatistics s = randomStatistics(rng, 50, 21, 3);
  std::vector<uint8_t> wire;
  encodeRefinementStatistics(s, wire);
  RefinementStatistics back;
  std::string error;
  for (size_t cut : {size_t(0), size_t(5), wire.size() / 2, wire.size() - 1}) {
    error = decodeRefinementStatistics(std::span(wire.data(), cut), back).error();
    EXPECT_FALSE(error.empty());
  }
  std::vector<uint8_t> bad = wire;
  bad[5] = 9;  // colour bits
  EXPECT_FALSE(decodeRefinementStatistics(bad, back).ok());
  bad = wire;
  bad[0] = 0xff, bad[1] = 0xff, bad[2] = 0xff;  // absurd vertex count
  EXPECT_FALSE(decodeRefinementStatistics(bad, back).ok());
  // 50 points: the contour's last byte holds 2 of them; a bit beyond is no point's.
  bad = wire;
  bad.back() |= 0x80;
  error = decodeRefinementStatistics(bad, back).error();
  EXPECT_EQ(error, "refinement statistics: contour bits past its points");
  RefinementStatistics sum;
  sum.reset(50, 21, 6);
  EXPECT_EQ(addEncodedRefinementStatistics(bad, sum).error(),
            "refinement statistics: contour bits past its points");
  EXPECT_EQ(decodeRefinementStatistics(wire, back).error(), "");
}

TEST(RefinementStatistics, CompressedWireRoundTripsExactly) {
  std::mt19937 rng(10);
  RefinementStatisticsCodec codec, other_codec;
  for (int cameras : {1, 3, 8}) {
    const RefinementStatistics s = randomStatistics(rng, 300, 21, cameras);
    std::vector<uint8_t> packed, wire, again;
    encodeRefinementStatistics(s, packed);
    codec.encode(s, wire);
    ASSERT_TRUE(isCompressedRefinementStatistics(wire));
    EXPECT_FALSE(isCompressedRefinementStatistics(packed));
    EXPECT_LT(wire.size(), packed.size()) << cameras << " cameras";
    // The sizes stay readable in place for the studio; the rest is one zstd frame.
    EXPECT_TRUE(std::equal(packed.begin(), packed.begin() + 6, wire.begin()));
    RefinementStatistics back, back_free;
    ASSERT_EQ(other_codec.decode(wire, back).error(), "");
    EXPECT_TRUE(back == s) << cameras << " cameras";
    ASSERT_EQ(decodeRefinementStatistics(wire, back_free).error(), "");
    EXPECT_TRUE(back_free == s);
    // The codec reads the packed form too, and a reused codec writes the same bytes.
    ASSERT_EQ(other_codec.decode(packed, back).error(), "");
    EXPECT_TRUE(back == s);
    codec.encode(s, again);
    EXPECT_EQ(again, wire);
  }
}

TEST(RefinementStatistics, CompressedAddEqualsPackedAdd) {
  std::mt19937 rng(11);
  RefinementStatisticsCodec codec;
  RefinementStatistics from_packed, from_compressed, from_free, from_structs;
  for (RefinementStatistics* sum : {&from_packed, &from_compressed, &from_free, &from_structs})
    sum->reset(120, 21, 6);
  std::vector<uint8_t> packed, wire;
  for (int n = 0; n < 4; ++n) {
    const RefinementStatistics s = randomStatistics(rng, 120, 21, 3);
    encodeRefinementStatistics(s, packed);
    codec.encode(s, wire);
    ASSERT_EQ(addEncodedRefinementStatistics(packed, from_packed).error(), "");
    ASSERT_EQ(codec.add(wire, from_compressed).error(), "");
    ASSERT_EQ(addEncodedRefinementStatistics(wire, from_free).error(), "");
    ASSERT_TRUE(from_structs.add(s));
  }
  EXPECT_TRUE(from_compressed == from_packed);
  EXPECT_TRUE(from_free == from_packed);
  // And, once the colour outside and the edges inside are dropped, what add() gives.
  from_packed.dropOutside();
  EXPECT_TRUE(from_packed == from_structs);
}

// What a hostile or broken node could send: every case refused with its reason, nothing changed,
// nothing decompressed beyond the bound of the header's sample count.
TEST(RefinementStatistics, HostileCompressedWireIsRefused) {
  std::mt19937 rng(12);
  const RefinementStatistics s = randomStatistics(rng, 50, 21, 3);
  RefinementStatisticsCodec codec;
  std::vector<uint8_t> packed, wire;
  encodeRefinementStatistics(s, packed);
  codec.encode(s, wire);
  ASSERT_TRUE(isCompressedRefinementStatistics(wire));
  RefinementStatistics sum;
  sum.reset(50, 21, 6);
  const RefinementStatistics untouched = sum;
  auto refusal = [&](const std::vector<uint8_t>& bad) {
    RefinementStatistics back;
    const std::string decode_error = codec.decode(bad, back).error();
    const std::string add_error = codec.add(bad, sum).error();
    EXPECT_TRUE(sum == untouched);
    EXPECT_EQ(add_error, decode_error);
    return decode_error;
  };
  auto withSize = [&](uint32_t size) {
    std::vector<uint8_t> bad = wire;
    for (int i = 0; i < 4; ++i) bad[8 + i] = uint8_t(size >> (8 * i));
    return bad;
  };
  const std::string why = "refinement statistics: ";

  EXPECT_EQ(refusal({wire.begin(), wire.begin() + 10}), why + "shorter than its compressed header");
  EXPECT_EQ(refusal({wire.begin(), wire.begin() + 14}),
            why + "compressed form does not hold a zstd frame");
  EXPECT_EQ(refusal({wire.begin(), wire.begin() + 17}),
            why + "malformed or truncated zstd frame header");
  EXPECT_EQ(refusal({wire.begin(), wire.end() - 1}).rfind(why + "truncated zstd frame: ", 0), 0u);
  std::vector<uint8_t> bad = wire;
  bad.push_back(0);
  EXPECT_EQ(refusal(bad), why + "bytes after the zstd frame");
  bad = wire;
  bad[7] = 2;
  EXPECT_EQ(refusal(bad), why + "unknown compression 2");

  // Declared sizes: above the bound of 50 x 21 samples (8 + 12 a sample and a contour bit for as
  // many points), below their counts and the 50 points' contour bits, or other than the frame's
  // own.
  EXPECT_EQ(refusal(withSize(12741)),
            why + "compressed form declares 12741 packed bytes, 1050 samples take 1065 to 12740");
  EXPECT_EQ(refusal(withSize(1064)),
            why + "compressed form declares 1064 packed bytes, 1050 samples take 1065 to 12740");
  EXPECT_EQ(refusal(withSize(uint32_t(packed.size() + 1))),
            why + "zstd frame declares " + std::to_string(packed.size()) + " bytes, the header " +
                std::to_string(packed.size() + 1));

  // Corrupt data: the checksum catches what the zstd format itself does not.
  bad = wire;
  bad.back() ^= 0x5a;
  EXPECT_EQ(refusal(bad), why + "corrupt zstd frame: Restored data doesn't match checksum");
  for (size_t at = 20; at + 8 < wire.size(); at += 97) {
    bad = wire;
    bad[at] ^= 0x5a;
    EXPECT_EQ(refusal(bad).rfind(why, 0), 0u) << at;
  }
  // A frame that decompresses well but holds statistics other than its header says.
  bad = wire;
  bad[5] = 5;  // colour bits
  RefinementStatistics back;
  std::string error;
  error = codec.decode(bad, back).error();
  EXPECT_EQ(error, why + "the packed header differs from the compressed one");
  // Too many samples for the reader, or another mesh's sizes: refused before decompressing.
  error = codec.decode(wire, back, 1000).error();
  EXPECT_EQ(error, why + "too many samples");
  RefinementStatistics other;
  other.reset(51, 21, 6);
  error = codec.add(wire, other).error();
  EXPECT_EQ(error, why + "sizes differ from the mesh's");
  // And the codec still works after all that.
  ASSERT_EQ(codec.decode(wire, back).error(), "");
  EXPECT_TRUE(back == s);
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
  // Sums are the plain sums where no node saw the sample outside; nothing where one did. Edges
  // are the innermost of the nodes' where the combined hull leaves; nothing elsewhere.
  int edges = 0;
  for (int i = 0; i < forward.sampleCount(); ++i) {
    int outside = 0, count = 0, innermost = 256;
    uint32_t squares = 0;
    for (const auto& n : nodes) {
      outside += n.outside[i], count += n.colour_count[i], squares += n.squares[i];
      if (n.edges[i] != 0) innermost = std::min<int>(innermost, n.edges[i]);
    }
    EXPECT_EQ(forward.outside[i], outside);
    EXPECT_EQ(forward.colour_count[i], outside ? 0 : count);
    EXPECT_EQ(forward.squares[i], outside ? 0 : squares);
    const bool leaves = forward.leavesHull(i);
    EXPECT_EQ(forward.edges[i], leaves && innermost < 256 ? innermost : 0) << i;
    edges += forward.edges[i] != 0;
  }
  EXPECT_GT(edges, 20);  // the case is exercised
  // A point is on the combined set's contour where it is on any node's.
  int contour = 0;
  for (int v = 0; v < 200; ++v) {
    const bool any = std::any_of(nodes.begin(), nodes.end(),
                                 [&](const RefinementStatistics& n) { return n.contour[v] != 0; });
    EXPECT_EQ(forward.contour[v], any ? 1 : 0) << v;
    contour += forward.contour[v];
  }
  EXPECT_GT(contour, 100);  // 1 - (3/4)^4 of them
  EXPECT_LT(contour, 200);
  RefinementStatistics other;
  other.reset(201, 21, 6);
  EXPECT_FALSE(forward.add(other));
}

}  // namespace
}  // namespace lumistage
