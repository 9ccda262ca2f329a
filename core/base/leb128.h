#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace lumistage {

// Unsigned LEB128 varints, as the wire's run lengths are written (partial images' alpha runs,
// silhouettes' runs): seven bits a byte, least significant first, the top bit set on every byte
// but the last.
inline void appendLeb128(uint64_t v, std::vector<uint8_t>& out) {
  while (v >= 0x80) {
    out.push_back(static_cast<uint8_t>(v | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<uint8_t>(v));
}

// The varint at data[at] into `v`, `at` moved past it. False when it is cut short by the end of
// `data` (then at == data.size()) or longer than 64 bits.
inline bool readLeb128(std::span<const uint8_t> data, size_t& at, uint64_t& v) {
  v = 0;
  for (int shift = 0; shift < 64; shift += 7) {
    if (at >= data.size()) return false;
    const uint8_t b = data[at++];
    v |= uint64_t(b & 0x7f) << shift;
    if (!(b & 0x80)) return true;
  }
  return false;
}

}  // namespace lumistage
