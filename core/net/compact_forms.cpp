#include "core/net/compact_forms.h"

#include <zstd.h>

#include "core/base/leb128.h"
#include "core/imaging/partial_image_codec.h"

namespace lumistage {

namespace {

// A thread's zstd contexts for the partial images (made on first use, kept until it ends): the
// codec's functions are free functions, called from the nodes' and the studio's message threads.
struct ImageZstd {
  ZSTD_CCtx* c = nullptr;
  ZSTD_DCtx* d = nullptr;
  ~ImageZstd() {
    ZSTD_freeCCtx(c);
    ZSTD_freeDCtx(d);
  }
};
thread_local ImageZstd image_zstd;

}  // namespace

void encodeMaskRuns(std::span<const uint8_t> bits, size_t cells, std::vector<uint8_t>& out) {
  out.clear();
  bool on = false;
  size_t start = 0, i = 0;
  while (i < cells) {
    // Whole bytes of the run's kind at once (most of a mask is off the actor).
    if ((i & 7) == 0 && i + 8 <= cells && bits[i >> 3] == (on ? 0xff : 0x00)) {
      i += 8;
      continue;
    }
    if (((bits[i >> 3] >> (i & 7)) & 1u) != unsigned(on)) {
      appendLeb128(i - start, out);
      start = i;
      on = !on;
    }
    ++i;
  }
  appendLeb128(cells - start, out);
}

bool decodeMaskRuns(std::span<const uint8_t> runs, size_t cells, std::vector<uint8_t>& bits,
                    std::string& why) {
  bits.assign((cells + 7) / 8, 0);
  size_t covered = 0, at = 0;
  bool on = false;
  while (at < runs.size()) {
    const size_t first = at;
    uint64_t run;
    if (!readLeb128(runs, at, run)) {
      why = "runs: the length at byte " + std::to_string(first) +
            (at == runs.size() ? " is cut short" : " is too long");
      return false;
    }
    if (run > cells - covered) {
      why = "runs: the run at byte " + std::to_string(first) + " reaches pixel " +
            std::to_string(covered + run) + ", the mask has " + std::to_string(cells);
      return false;
    }
    if (on)
      for (size_t i = covered; i < covered + run; ++i) bits[i >> 3] |= uint8_t(1u << (i & 7));
    covered += run;
    on = !on;
  }
  if (covered != cells) {
    why = "runs cover " + std::to_string(covered) + " of the mask's " + std::to_string(cells) +
          " pixels";
    return false;
  }
  return true;
}

bool compressAlphaRuns(std::span<const uint8_t> alpha_runs, size_t pixel_count,
                       std::vector<uint8_t>& scratch, std::vector<uint8_t>& out) {
  scratch.assign(alpha_runs.begin(), alpha_runs.end());
  if (!differenceAlphaRunLiterals(scratch, pixel_count, false)) return false;
  if (!image_zstd.c) {
    image_zstd.c = ZSTD_createCCtx();
    if (!image_zstd.c) return false;
    ZSTD_CCtx_setParameter(image_zstd.c, ZSTD_c_compressionLevel, 1);
    ZSTD_CCtx_setParameter(image_zstd.c, ZSTD_c_checksumFlag, 1);
  }
  out.resize(ZSTD_compressBound(scratch.size()));
  const size_t n =
      ZSTD_compress2(image_zstd.c, out.data(), out.size(), scratch.data(), scratch.size());
  if (ZSTD_isError(n) || n >= alpha_runs.size()) return false;
  out.resize(n);
  return true;
}

bool decompressAlphaRuns(std::span<const uint8_t> compressed, size_t pixel_count,
                         std::vector<uint8_t>& alpha_runs, std::string& why) {
  const std::string what =
      "compressed alpha-run data of " + std::to_string(compressed.size()) + " bytes";
  // The alpha runs' largest form: a varint pair (at most 3 bytes each below 2^21 pixels) before
  // every literal pixel.
  const uint64_t largest = uint64_t(pixel_count) * 10 + 20;
  const unsigned long long size = ZSTD_getFrameContentSize(compressed.data(), compressed.size());
  if (size == ZSTD_CONTENTSIZE_ERROR || size == ZSTD_CONTENTSIZE_UNKNOWN || size > largest) {
    why = what + " is not one zstd frame of at most " + std::to_string(largest) + " bytes";
    return false;
  }
  if (!image_zstd.d && !(image_zstd.d = ZSTD_createDCtx())) {
    why = "no memory to decompress it";
    return false;
  }
  alpha_runs.resize(size_t(size));
  const size_t n = ZSTD_decompressDCtx(image_zstd.d, alpha_runs.data(), alpha_runs.size(),
                                       compressed.data(), compressed.size());
  if (ZSTD_isError(n) || n != size) {
    why = what + " is corrupt" +
          (ZSTD_isError(n) ? std::string(" (") + ZSTD_getErrorName(n) + ")" : std::string());
    return false;
  }
  if (!differenceAlphaRunLiterals(alpha_runs, pixel_count, true)) {
    why = what + " does not cover exactly " + std::to_string(pixel_count) + " pixels";
    return false;
  }
  return true;
}

}  // namespace lumistage
