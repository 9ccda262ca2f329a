#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

namespace lumistage {

// The two encodings of a partial image on the wire (ImageEncoding in core/net/message_codec.h),
// plain functions over bytes below both the message codec, which checks them, and the renderer,
// which blends from them.
//
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

// In place, each literal byte of a valid encoding made its difference from the byte 4 before it
// in the same run (the run's first pixel as it is), or, with `undo`, made back: neighbouring
// pixels differ little, and the differences compress (the wire's alpha_runs_zstd). False, with
// `data` changed up to where it stopped being one, when it is not a valid encoding of exactly
// pixel_count pixels (the run lengths are not changed, so either way round checks the same).
bool differenceAlphaRunLiterals(std::span<uint8_t> data, size_t pixel_count, bool undo);

// Calls run(first_pixel, rgba, count) for every run of literal pixels (`rgba` points at its
// count*4 bytes in `data`), in order, without touching the empty pixels: the studio blends the
// nodes' images straight from the wire. Returns false, having called nothing, when `data` is not
// a valid encoding of exactly pixel_count pixels.
bool forEachLiteralRun(std::span<const uint8_t> data, size_t pixel_count,
                       const std::function<void(size_t, const uint8_t*, size_t)>& run);

// The rle_rgba encoding of PartialImage: runs of up to 256 equal pixels as 5 bytes (length-1,
// R, G, B, A). Mostly transparent partial renders shrink a lot.
std::vector<uint8_t> encodeRleRgba(std::span<const uint8_t> rgba);
// Empty when `rle` is not a valid encoding of exactly pixel_count pixels.
std::vector<uint8_t> decodeRleRgba(std::span<const uint8_t> rle, size_t pixel_count);

}  // namespace lumistage
