#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace lumistage {

// What the refinement needs to know, per vertex v and offset t (sample s = v·offset_count + t),
// from a set of cameras (DESIGN.md §1): how many see the point outside their silhouette, and the
// colour statistics of those that see it (visible in their depth map) inside it — count, sums
// and the sum of squares over channels, in integers of `colour_bits` a channel. Integer sums make
// the combination of nodes exact and independent of order. A sample that any camera sees outside
// the hull keeps no colour (the error does not use it there), so that combining nodes gives
// bit for bit the statistics of one process holding every camera.
struct RefinementStatistics {
  int vertex_count = 0;
  int offset_count = 0;
  int colour_bits = 6;
  std::vector<uint8_t> outside;       // per sample
  std::vector<uint8_t> colour_count;  // per sample
  std::vector<uint16_t> sums;         // per sample: R, G, B
  std::vector<uint32_t> squares;      // per sample: Σ over cameras and channels of c²

  int sampleCount() const { return vertex_count * offset_count; }
  // Sizes and zeroes everything; allocates only when the size grows.
  void reset(int vertices, int offsets, int bits);
  // Adds another set's counts and sums (same sizes), then drops the colour of samples now seen
  // outside. Exact. Returns false (and changes nothing) when the sizes differ.
  bool add(const RefinementStatistics& other);
  // Drops the colour of every sample seen outside.
  void dropColourOutside();
  bool operator==(const RefinementStatistics&) const = default;
};

// The compact wire form: a header (vertex count, offset count, colour bits, the byte widths of
// sums and squares), then one byte a sample (outside count in the low nibble, colour count in the
// high one, each at most 15), then the sums of the samples with colour and the squares of those
// seen by two cameras or more (one camera's square follows from its sum), little endian, in the
// narrowest widths their largest values need. `out` is reused.
void encodeRefinementStatistics(const RefinementStatistics& stats, std::vector<uint8_t>& out);
// Empty (with `error` set when given) for a malformed or truncated buffer, or sizes above
// max_samples. `out` is reused.
bool decodeRefinementStatistics(std::span<const uint8_t> data, RefinementStatistics& out,
                                std::string* error = nullptr, int max_samples = 1 << 22);
// The module's fast path: adds a node's wire form to `sum` (of the same sizes) without decoding it
// first; call sum.dropColourOutside() after the last node. The result is what decoding and add()
// give. False (`sum` unchanged) for a malformed buffer or other sizes.
bool addEncodedRefinementStatistics(std::span<const uint8_t> data, RefinementStatistics& sum,
                                    std::string* error = nullptr);

}  // namespace lumistage
