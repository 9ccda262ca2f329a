#include "core/imaging/partial_image_codec.h"

#include <cstring>

#include "core/base/leb128.h"

namespace lumistage {

namespace {

bool empty(const uint8_t* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v == 0;
}

}  // namespace

void encodeAlphaRuns(std::span<const uint8_t> rgba, std::vector<uint8_t>& out) {
  out.clear();
  const size_t n = rgba.size() / 4;
  const uint8_t* p = rgba.data();
  size_t i = 0;
  while (i < n) {
    size_t e = i;
    while (e < n && empty(p + 4 * e)) ++e;
    size_t l = e;
    while (l < n && !empty(p + 4 * l)) ++l;
    appendLeb128(e - i, out);
    appendLeb128(l - e, out);
    out.insert(out.end(), p + 4 * e, p + 4 * l);
    i = l;
  }
}

namespace {

// The one walk over an encoding: checks it as it goes and calls run(first_pixel, rgba, count)
// for every run of literal pixels. False as soon as it is not an encoding of exactly pixel_count
// pixels (runs before that were called).
template <typename Run>
bool walkAlphaRuns(std::span<const uint8_t> data, size_t pixel_count, Run&& run) {
  size_t at = 0, i = 0;
  while (i < pixel_count) {
    uint64_t empty_run = 0, literal_run = 0;
    if (!readLeb128(data, at, empty_run) || !readLeb128(data, at, literal_run)) return false;
    if (empty_run > pixel_count - i || literal_run > pixel_count - i - empty_run) return false;
    if (empty_run + literal_run == 0) return false;  // no progress: not an encoding of ours
    i += empty_run;
    if (literal_run * 4 > data.size() - at) return false;
    if (literal_run > 0) run(i, data.data() + at, size_t(literal_run));
    at += 4 * literal_run;
    i += literal_run;
  }
  return at == data.size();
}

}  // namespace

bool decodeAlphaRuns(std::span<const uint8_t> data, size_t pixel_count,
                     std::vector<uint8_t>& rgba) {
  rgba.assign(pixel_count * 4, 0);
  return walkAlphaRuns(data, pixel_count, [&](size_t first, const uint8_t* p, size_t count) {
    std::memcpy(rgba.data() + 4 * first, p, 4 * count);
  });
}

bool validAlphaRuns(std::span<const uint8_t> data, size_t pixel_count) {
  return walkAlphaRuns(data, pixel_count, [](size_t, const uint8_t*, size_t) {});
}

bool differenceAlphaRunLiterals(std::span<uint8_t> data, size_t pixel_count, bool undo) {
  uint8_t* const base = data.data();
  return walkAlphaRuns(data, pixel_count, [&](size_t, const uint8_t* run, size_t count) {
    uint8_t* p = base + (run - base);  // the walk reads `data`, which is ours to change
    const size_t bytes = count * 4;
    if (undo) {
      for (size_t t = 4; t < bytes; ++t) p[t] = uint8_t(p[t] + p[t - 4]);
    } else {
      for (size_t t = bytes; t-- > 4;) p[t] = uint8_t(p[t] - p[t - 4]);
    }
  });
}

bool forEachLiteralRun(std::span<const uint8_t> data, size_t pixel_count,
                       const std::function<void(size_t, const uint8_t*, size_t)>& run) {
  return validAlphaRuns(data, pixel_count) && walkAlphaRuns(data, pixel_count, run);
}

std::vector<uint8_t> encodeRleRgba(std::span<const uint8_t> rgba) {
  std::vector<uint8_t> out;
  const size_t pixels = rgba.size() / 4;
  for (size_t i = 0; i < pixels;) {
    size_t run = 1;
    while (run < 256 && i + run < pixels &&
           std::memcmp(&rgba[4 * i], &rgba[4 * (i + run)], 4) == 0) {
      ++run;
    }
    out.push_back(static_cast<uint8_t>(run - 1));
    out.insert(out.end(), rgba.begin() + 4 * i, rgba.begin() + 4 * i + 4);
    i += run;
  }
  return out;
}

std::vector<uint8_t> decodeRleRgba(std::span<const uint8_t> rle, size_t pixel_count) {
  if (rle.size() % 5 != 0) return {};
  std::vector<uint8_t> out;
  out.reserve(pixel_count * 4);
  for (size_t i = 0; i < rle.size(); i += 5) {
    const size_t run = size_t{rle[i]} + 1;
    if (out.size() / 4 + run > pixel_count) return {};
    for (size_t k = 0; k < run; ++k)
      out.insert(out.end(), rle.begin() + i + 1, rle.begin() + i + 5);
  }
  if (out.size() != pixel_count * 4) return {};
  return out;
}

}  // namespace lumistage
