#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/base/status.h"

struct ZSTD_CCtx_s;
struct ZSTD_DCtx_s;

namespace lumistage {

// What the refinement needs to know, per vertex v and offset t (sample s = v·offset_count + t),
// from a set of cameras (DESIGN.md §1): how many see the point outside their silhouette, and the
// colour statistics of those that see it (visible in their depth map) inside it — count, sums
// and the sum of squares over channels, in integers of `colour_bits` a channel. Integer sums make
// the combination of nodes exact and independent of order. A sample that any camera sees outside
// the hull keeps no colour (the error does not use it there), so that combining nodes gives
// bit for bit the statistics of one process holding every camera.
//
// And where the hull's surface lies between two samples, finer than their spacing: where sample s
// is inside the set's hull and s + 1 (of the same vertex) outside it, edges[s] in 1..255 puts the
// edge at (edges[s] - 1) / 254 of the step from s to s + 1 — the innermost of the silhouette edges
// that the set's cameras cross there, each located below a pixel (RefinementSampler); 0 when none
// was located. Sets combine by the innermost edge, which is the hull's: exact too.
//
// And per point, whether one of the set's cameras sees it on its silhouette's contour (contour[v],
// RefinementSampler): where the visual hull touches the surface, so that the hull's crossing along
// the point's normal is the surface itself rather than a bound on it. Sets combine by either.
struct RefinementStatistics {
  int vertex_count = 0;
  int offset_count = 0;
  int colour_bits = 6;
  std::vector<uint8_t> outside;       // per sample
  std::vector<uint8_t> colour_count;  // per sample
  std::vector<uint16_t> sums;         // per sample: R, G, B
  std::vector<uint32_t> squares;      // per sample: Σ over cameras and channels of c²
  std::vector<uint8_t> edges;         // per sample: 0, or the hull's edge toward s + 1
  std::vector<uint8_t> contour;       // per point (vertex_count): 1 on a camera's contour, else 0

  static constexpr int kEdgeLevels = 254;  // an edge's fraction of a step: (edges[s] - 1) / 254
  // The innermost of two edges, either possibly absent (0).
  static uint8_t innerEdge(uint8_t a, uint8_t b) {
    return a == 0 ? b : (b == 0 ? a : (a < b ? a : b));
  }

  int sampleCount() const { return vertex_count * offset_count; }
  // Whether the hull leaves between sample s and the next of its vertex: s inside, s + 1 outside.
  bool leavesHull(size_t s) const {
    return outside[s] == 0 && (s + 1) % size_t(offset_count) != 0 && outside[s + 1] > 0;
  }
  // Sizes and zeroes everything; allocates only when the size grows.
  void reset(int vertices, int offsets, int bits);
  // Adds another set's counts and sums (same sizes), keeps the innermost edges, then drops the
  // colour of samples now seen outside and the edges where the hull no longer leaves. Exact.
  // Returns false (and changes nothing) when the sizes differ.
  bool add(const RefinementStatistics& other);
  // Drops the colour of every sample seen outside and every edge where the hull does not leave.
  void dropOutside();
  bool operator==(const RefinementStatistics&) const = default;
};

// The wire form comes in two kinds, told apart by byte 6 of the header; both decoders below take
// either.
//
// Packed (encodeRefinementStatistics): a header (vertex count, offset count, colour bits, the byte
// widths of sums and squares), then one byte a sample (outside count in the low nibble, colour
// count in the high one, each at most 15), then the values, little endian, in the narrowest widths
// they need: the sums of the samples with colour, channel by channel (every red sum, then every
// green, then every blue), each as its difference from the channel's sum at the sample with colour
// before it (modulo the width); then, for the samples seen by two cameras or more (one camera's
// square follows from its sum), the square less (R² + G² + B²) / k of the sums (k the packed
// colour count, rounded down; modulo 2^32), k times the colour's variance, which is small where
// the cameras agree. Then one byte for every sample where the hull leaves (leavesHull()): its
// edge. The differences and the variances are what makes the form compress: a third less than
// the sums and squares as they are, on a node's statistics (docs/lumigraph.md). Last, the points'
// contour flags, a bit each (point v: bit v % 8 of byte v / 8).
//
// Compressed (RefinementStatisticsCodec::encode, what nodes send): the packed form's vertex count,
// offset count and colour bits in the same places, then 0 where the packed form has its sums'
// width (1 or 2: a reader of the packed form alone refuses it), the compression (1: zstd), the
// packed form's size (4 bytes), then one zstd frame (with content size and checksum) holding the
// whole packed form.
inline constexpr size_t kPackedStatisticsHeaderBytes = 8;
inline constexpr size_t kCompressedStatisticsHeaderBytes = 12;
// The contour flags' bytes of `points` points.
inline constexpr uint64_t contourBytes(uint64_t points) {
  return (points + 7) / 8;
}
// The largest packed form of `samples` samples: a count, 2-byte sums, a 4-byte square and an edge
// each, and a contour bit for each of at most as many points.
inline constexpr uint64_t maxPackedStatisticsBytes(uint64_t samples) {
  return kPackedStatisticsHeaderBytes + samples * 12 + contourBytes(samples);
}
// The largest compressed form of `samples` samples: the header and zstd's bound for the largest
// packed form (ZSTD_COMPRESSBOUND).
inline constexpr uint64_t maxCompressedStatisticsBytes(uint64_t samples) {
  const uint64_t packed = maxPackedStatisticsBytes(samples);
  return kCompressedStatisticsHeaderBytes + packed + (packed >> 8) +
         (packed < (128 << 10) ? ((128 << 10) - packed) >> 11 : 0);
}
inline bool isCompressedRefinementStatistics(std::span<const uint8_t> data) {
  return data.size() >= kPackedStatisticsHeaderBytes && data[6] == 0;
}

// The packed form. `out` is reused.
void encodeRefinementStatistics(const RefinementStatistics& stats, std::vector<uint8_t>& out);
// Fails for a malformed, truncated or corrupt buffer of either form, or sizes above max_samples,
// saying why. `out` is reused. The compressed form goes through this thread's
// own codec (made on first use, kept until the thread ends); hot paths hold a codec instead.
Status decodeRefinementStatistics(std::span<const uint8_t> data, RefinementStatistics& out,
                                  int max_samples = 1 << 22);
// The module's fast path: adds a node's wire form (either kind) to `sum` (of the same sizes)
// without unpacking it into statistics first; call sum.dropOutside() after the last node.
// The result is what decoding and add() give. Fails (`sum` unchanged) for a malformed buffer or
// other sizes.
Status addEncodedRefinementStatistics(std::span<const uint8_t> data, RefinementStatistics& sum);

// The compressed wire form with reusable state: zstd contexts (made on first use: a node only
// compresses, the module only decompresses) and the packed form in between. Once warmed up by a
// frame of the largest size, encoding, decoding and adding allocate nothing (beyond `out` growing
// in encode). One codec a thread: the node's statistics thread and the studio's message loop
// each own one, so that a codec's lifetime is its owner's and no hidden per-thread state is needed
// on the hot paths. Decompression never allocates more than the packed form's bound for the
// header's sample count (maxPackedStatisticsBytes), checked before anything is decompressed.
class RefinementStatisticsCodec {
 public:
  static constexpr int kZstdLevel = 1;  // ~3.3x on a node's statistics at ~350-400 MB/s
  // Its match finder's table: 4096 entries (16 KB, in a core's first-level cache) instead of level
  // 1's 16384. A node's statistics (461 KB packed, refine_bench): 0.6% smaller and 1.30 -> 1.14 ms
  // (best of 30, alternating); 2^11: no better.
  static constexpr int kZstdHashLog = 12;

  RefinementStatisticsCodec();
  ~RefinementStatisticsCodec();
  RefinementStatisticsCodec(RefinementStatisticsCodec&&) noexcept;
  RefinementStatisticsCodec& operator=(RefinementStatisticsCodec&&) noexcept;

  // The compressed form of `stats` into `out` (reused). Never fails: should zstd fail (out of
  // memory), `out` is the packed form, which every reader takes too.
  void encode(const RefinementStatistics& stats, std::vector<uint8_t>& out);
  // As decodeRefinementStatistics and addEncodedRefinementStatistics, with this codec's state.
  Status decode(std::span<const uint8_t> data, RefinementStatistics& out,
                int max_samples = 1 << 22);
  Status add(std::span<const uint8_t> data, RefinementStatistics& sum);

 private:
  // The packed form of `data`: itself when packed, else decompressed into packed_ once the
  // compressed header and the frame's declared size agree and fit max_samples. Fails for anything
  // malformed.
  Status unpack(std::span<const uint8_t> data, int max_samples, std::span<const uint8_t>& packed);

  struct ZstdFree {
    void operator()(ZSTD_CCtx_s* c) const;
    void operator()(ZSTD_DCtx_s* d) const;
  };
  std::unique_ptr<ZSTD_CCtx_s, ZstdFree> compressor_;
  std::unique_ptr<ZSTD_DCtx_s, ZstdFree> decompressor_;
  std::vector<uint8_t> packed_;
};

}  // namespace lumistage
