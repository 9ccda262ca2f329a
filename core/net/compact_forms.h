#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace lumistage {

// The compact forms the message codec sends where they are smaller (messages.fbs), below the
// FlatBuffers tables: a silhouette's runs and a partial image's compressed alpha runs.

// A mask's `runs`: the lengths of alternating runs of `cells` pixels off and on the actor in
// `bits` ((cells + 7) / 8 bytes, bit i of byte i/8 is pixel i), as LEB128 varints, into `out`
// (reused).
void encodeMaskRuns(std::span<const uint8_t> bits, size_t cells, std::vector<uint8_t>& out);
// `runs` decoded into `bits` ((cells + 7) / 8 bytes); false, with `why` saying what and at which
// byte, unless the runs are well-formed varints that cover exactly `cells` pixels.
bool decodeMaskRuns(std::span<const uint8_t> runs, size_t cells, std::vector<uint8_t>& bits,
                    std::string& why);

// Alpha runs of `pixel_count` pixels (partial_image_codec.h) as alpha_runs_zstd: their literals'
// differences (differenceAlphaRunLiterals), one zstd frame with its content size and checksum,
// into `out`; `scratch` holds the differences. Both reused: no allocation once grown. False when
// that is no smaller than the alpha runs (or they are not a valid encoding).
bool compressAlphaRuns(std::span<const uint8_t> alpha_runs, size_t pixel_count,
                       std::vector<uint8_t>& scratch, std::vector<uint8_t>& out);
// The alpha runs of `pixel_count` pixels an alpha_runs_zstd form holds, into `alpha_runs`; false,
// with `why`, when it is not one zstd frame of at most their largest size, is corrupt, or does not
// hold a valid encoding of exactly pixel_count pixels.
bool decompressAlphaRuns(std::span<const uint8_t> compressed, size_t pixel_count,
                         std::vector<uint8_t>& alpha_runs, std::string& why);

}  // namespace lumistage
