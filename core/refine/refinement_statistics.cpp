#include "core/refine/refinement_statistics.h"

#include <algorithm>

namespace lumistage {

void RefinementStatistics::reset(int vertices, int offsets, int bits) {
  vertex_count = vertices;
  offset_count = offsets;
  colour_bits = bits;
  const size_t n = size_t(vertices) * offsets;
  outside.assign(n, 0);
  colour_count.assign(n, 0);
  sums.assign(3 * n, 0);
  squares.assign(n, 0);
}

bool RefinementStatistics::add(const RefinementStatistics& other) {
  if (other.vertex_count != vertex_count || other.offset_count != offset_count ||
      other.colour_bits != colour_bits || other.outside.size() != outside.size()) {
    return false;
  }
  const size_t n = outside.size();
  for (size_t s = 0; s < n; ++s) {
    outside[s] = uint8_t(std::min(255, outside[s] + other.outside[s]));
    colour_count[s] = uint8_t(std::min(255, colour_count[s] + other.colour_count[s]));
    squares[s] += other.squares[s];
  }
  for (size_t i = 0; i < 3 * n; ++i) sums[i] = uint16_t(sums[i] + other.sums[i]);
  dropColourOutside();
  return true;
}

void RefinementStatistics::dropColourOutside() {
  const size_t n = outside.size();
  for (size_t s = 0; s < n; ++s) {
    if (outside[s] == 0) continue;
    colour_count[s] = 0;
    squares[s] = 0;
    sums[3 * s] = sums[3 * s + 1] = sums[3 * s + 2] = 0;
  }
}

namespace {

constexpr size_t kHeaderBytes = 4 + 1 + 1 + 1 + 1;

int bytesFor(uint64_t max_value) {
  int b = 1;
  while (b < 4 && max_value >> (8 * b)) ++b;
  return b;
}

void put(std::vector<uint8_t>& out, size_t& at, uint32_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) out[at++] = uint8_t(value >> (8 * i));
}

uint32_t get(const uint8_t* p, int bytes) {
  uint32_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= uint32_t(p[i]) << (8 * i);
  return v;
}

}  // namespace

void encodeRefinementStatistics(const RefinementStatistics& stats, std::vector<uint8_t>& out) {
  const size_t n = stats.outside.size();
  uint32_t max_sum = 0, max_square = 0;
  size_t coloured = 0;
  size_t squared = 0;
  for (size_t s = 0; s < n; ++s) {
    if (stats.colour_count[s] == 0) continue;
    ++coloured;
    squared += stats.colour_count[s] > 1;
    max_sum = std::max({max_sum, uint32_t(stats.sums[3 * s]), uint32_t(stats.sums[3 * s + 1]),
                        uint32_t(stats.sums[3 * s + 2])});
    max_square = std::max(max_square, stats.squares[s]);
  }
  const int sum_bytes = std::min(2, bytesFor(max_sum)), square_bytes = bytesFor(max_square);
  out.resize(kHeaderBytes + n + coloured * 3 * sum_bytes + squared * square_bytes);
  size_t at = 0;
  put(out, at, uint32_t(stats.vertex_count), 4);
  out[at++] = uint8_t(stats.offset_count);
  out[at++] = uint8_t(stats.colour_bits);
  out[at++] = uint8_t(sum_bytes);
  out[at++] = uint8_t(square_bytes);
  for (size_t s = 0; s < n; ++s) {
    out[at++] = uint8_t(std::min<int>(stats.outside[s], 15) |
                        (std::min<int>(stats.colour_count[s], 15) << 4));
  }
  for (size_t s = 0; s < n; ++s) {
    if (stats.colour_count[s] == 0) continue;
    for (int c = 0; c < 3; ++c) put(out, at, stats.sums[3 * s + c], sum_bytes);
    if (stats.colour_count[s] > 1) put(out, at, stats.squares[s], square_bytes);
  }
}

bool decodeRefinementStatistics(std::span<const uint8_t> data, RefinementStatistics& out,
                                std::string* error, int max_samples) {
  auto fail = [&](const char* why) {
    if (error) *error = std::string("refinement statistics: ") + why;
    return false;
  };
  if (data.size() < kHeaderBytes) return fail("shorter than its header");
  const uint32_t vertices = get(data.data(), 4);
  const int offsets = data[4], bits = data[5], sum_bytes = data[6], square_bytes = data[7];
  if (offsets == 0 || bits < 1 || bits > 8) return fail("bad offset count or colour bits");
  if (sum_bytes < 1 || sum_bytes > 2 || square_bytes < 1 || square_bytes > 4)
    return fail("bad value widths");
  if (uint64_t(vertices) * offsets > uint64_t(max_samples)) return fail("too many samples");
  const size_t n = size_t(vertices) * offsets;
  if (data.size() < kHeaderBytes + n) return fail("truncated counts");
  const uint8_t* counts = data.data() + kHeaderBytes;
  size_t coloured = 0, squared = 0;
  for (size_t s = 0; s < n; ++s) coloured += (counts[s] >> 4) != 0, squared += (counts[s] >> 4) > 1;
  if (data.size() != kHeaderBytes + n + coloured * 3 * sum_bytes + squared * square_bytes)
    return fail("size does not match its counts");
  out.reset(int(vertices), offsets, bits);
  const uint8_t* p = counts + n;
  for (size_t s = 0; s < n; ++s) {
    out.outside[s] = counts[s] & 15;
    out.colour_count[s] = counts[s] >> 4;
    if (out.colour_count[s] == 0) continue;
    for (int c = 0; c < 3; ++c, p += sum_bytes) out.sums[3 * s + c] = uint16_t(get(p, sum_bytes));
    if (out.colour_count[s] == 1) {  // one camera: its colour is the sum
      uint32_t q = 0;
      for (int c = 0; c < 3; ++c) q += uint32_t(out.sums[3 * s + c]) * out.sums[3 * s + c];
      out.squares[s] = q;
      continue;
    }
    out.squares[s] = get(p, square_bytes);
    p += square_bytes;
  }
  return true;
}

bool addEncodedRefinementStatistics(std::span<const uint8_t> data, RefinementStatistics& sum,
                                    std::string* error) {
  auto fail = [&](const char* why) {
    if (error) *error = std::string("refinement statistics: ") + why;
    return false;
  };
  if (data.size() < kHeaderBytes) return fail("shorter than its header");
  const uint32_t vertices = get(data.data(), 4);
  const int offsets = data[4], bits = data[5], sum_bytes = data[6], square_bytes = data[7];
  if (int(vertices) != sum.vertex_count || offsets != sum.offset_count || bits != sum.colour_bits)
    return fail("sizes differ from the mesh's");
  if (sum_bytes < 1 || sum_bytes > 2 || square_bytes < 1 || square_bytes > 4)
    return fail("bad value widths");
  const size_t n = size_t(vertices) * offsets;
  if (data.size() < kHeaderBytes + n) return fail("truncated counts");
  const uint8_t* counts = data.data() + kHeaderBytes;
  size_t coloured = 0, squared = 0;
  for (size_t s = 0; s < n; ++s) {
    const int c = counts[s] >> 4;
    coloured += c != 0, squared += c > 1;
  }
  if (data.size() != kHeaderBytes + n + coloured * 3 * sum_bytes + squared * square_bytes)
    return fail("size does not match its counts");
  const uint8_t* p = counts + n;
  for (size_t s = 0; s < n; ++s) {
    const int outside = counts[s] & 15, colour = counts[s] >> 4;
    if (outside) sum.outside[s] = uint8_t(std::min(255, sum.outside[s] + outside));
    if (colour == 0) continue;
    sum.colour_count[s] = uint8_t(std::min(255, sum.colour_count[s] + colour));
    uint32_t q = 0;
    for (int c = 0; c < 3; ++c, p += sum_bytes) {
      const uint32_t v = sum_bytes == 1 ? p[0] : uint32_t(p[0] | (p[1] << 8));
      sum.sums[3 * s + c] = uint16_t(sum.sums[3 * s + c] + v);
      q += v * v;
    }
    if (colour > 1) {
      q = get(p, square_bytes);
      p += square_bytes;
    }
    sum.squares[s] += q;
  }
  return true;
}

}  // namespace lumistage
