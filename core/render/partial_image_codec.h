#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

namespace lumistage {

// Compression of the nodes' partial lumigraph images (RGBA8), which are mostly empty: the actor
// covers a fraction of the view and everything else is (0, 0, 0, 0). The "alpha runs" encoding
// alternates a run of empty pixels and a run of literal pixels, each length a LEB128 varint,
// the literal pixels as 4 bytes each:
//   (empty_run, literal_run, literal_run * RGBA)*
// until width*height pixels are covered. Exact for any RGBA (a pixel is empty only when all four
// bytes are 0). Against the paper's run-length encoding of equal pixels (rle_rgba: 5 bytes a
// run), it never spends more than 4 bytes on a noisy actor pixel; the figures are in
// docs/lumigraph.md.
void encodeAlphaRuns(std::span<const uint8_t> rgba, std::vector<uint8_t>& out);
// False (and `rgba` unspecified) when `data` is not a valid encoding of exactly pixel_count
// pixels. `rgba` is resized to pixel_count*4.
bool decodeAlphaRuns(std::span<const uint8_t> data, size_t pixel_count, std::vector<uint8_t>& rgba);

// Whether `data` is a valid encoding of exactly pixel_count pixels (no decoding, no allocation).
bool validAlphaRuns(std::span<const uint8_t> data, size_t pixel_count);

// Calls run(first_pixel, rgba, count) for every run of literal pixels (`rgba` points at its
// count*4 bytes in `data`), in order, without touching the empty pixels: the studio blends the
// nodes' images straight from the wire. Returns false, having called nothing, when `data` is not
// a valid encoding of exactly pixel_count pixels.
bool forEachLiteralRun(std::span<const uint8_t> data, size_t pixel_count,
                       const std::function<void(size_t, const uint8_t*, size_t)>& run);

}  // namespace lumistage
