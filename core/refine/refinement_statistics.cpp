#include "core/refine/refinement_statistics.h"

#include <zstd.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <bit>
#include <string_view>

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
  edges.assign(n, 0);
  contour.assign(size_t(vertices), 0);
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
    edges[s] = RefinementStatistics::innerEdge(edges[s], other.edges[s]);
  }
  for (size_t i = 0; i < 3 * n; ++i) sums[i] = uint16_t(sums[i] + other.sums[i]);
  for (size_t v = 0; v < contour.size(); ++v) contour[v] |= other.contour[v];
  dropOutside();
  return true;
}

void RefinementStatistics::dropOutside() {
  const size_t n = outside.size();
  for (size_t s = 0; s < n; ++s) {
    if (edges[s] != 0 && !leavesHull(s)) edges[s] = 0;
    if (outside[s] == 0) continue;
    colour_count[s] = 0;
    squares[s] = 0;
    sums[3 * s] = sums[3 * s + 1] = sums[3 * s + 2] = 0;
  }
}

namespace {

constexpr size_t kHeaderBytes = kPackedStatisticsHeaderBytes;
constexpr uint8_t kZstdCompression = 1;

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

// Bit i set where byte i of the 64 from `bytes` has a bit of `mask` set.
inline uint64_t nonZeroBytes64(const uint8_t* bytes, uint8_t mask) {
  uint64_t bits = 0;
#if defined(__SSE2__)
  const __m128i m = _mm_set1_epi8(char(mask)), zero = _mm_setzero_si128();
  for (int k = 0; k < 4; ++k) {
    const __m128i x =
        _mm_and_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(bytes + 16 * k)), m);
    const uint32_t none = uint32_t(_mm_movemask_epi8(_mm_cmpeq_epi8(x, zero)));
    bits |= uint64_t(~none & 0xffffu) << (16 * k);
  }
#else
  for (int i = 0; i < 64; ++i) bits |= uint64_t((bytes[i] & mask) != 0) << i;
#endif
  return bits;
}

// Calls f(s), in order, for every sample s of the n where the hull leaves (RefinementStatistics::
// leavesHull()): sample s is outside where outside[s] & mask is not 0. Sixty-four samples at a
// time as the bits of a word: the module runs this over every node's samples, and a pass a sample
// at a time cost it more than half a millisecond a frame.
template <typename F>
void forEachLeaving(const uint8_t* outside, uint8_t mask, size_t n, int offsets, const F& f) {
  if (offsets < 2) return;
  const size_t m = size_t(offsets);
  size_t s = 0, phase = 0;  // phase: s % m, the sample's place in its vertex
  for (; s + 64 < n; s += 64, phase = (phase + 64) % m) {
    const uint64_t out = nonZeroBytes64(outside + s, mask);
    const uint64_t after = (outside[s + 64] & mask) != 0;
    // Bit i: sample s + i inside, the next outside; not where s + i is its vertex's last.
    uint64_t leaving = ~out & ((out >> 1) | (after << 63));
    for (size_t last = m - 1 - phase; last < 64; last += m) leaving &= ~(uint64_t(1) << last);
    for (; leaving != 0; leaving &= leaving - 1) f(s + size_t(std::countr_zero(leaving)));
  }
  for (; s + 1 < n; ++s, phase = phase + 1 == m ? 0 : phase + 1)
    if (phase != m - 1 && !(outside[s] & mask) && (outside[s + 1] & mask)) f(s);
}

// A sample's colour count as the packed form holds it (a nibble).
inline int packedCount(int count) {
  return std::min(count, 15);
}

inline uint32_t sumOfSquares(const uint16_t* sums) {
  return uint32_t(sums[0]) * sums[0] + uint32_t(sums[1]) * sums[1] + uint32_t(sums[2]) * sums[2];
}
// (R² + G² + B²) / k of a sample's sums, rounded down.
inline uint32_t meanSquare(const uint16_t* sums, int k) {
  return sumOfSquares(sums) / uint32_t(k);
}
// What the packed form stores for the square of a sample seen by k >= 2 cameras: the square less
// meanSquare(), which Cauchy-Schwarz keeps between 0 and the square. It is k times the colour's
// variance over the cameras, summed over the channels: small where they agree, as they do near
// the surface. (Modulo 2^32, so that any values round-trip.)
inline uint32_t squareResidual(uint32_t square, const uint16_t* sums, int k) {
  return square - meanSquare(sums, k);
}

// A run of `count` values of `bytes` bytes each, as byte planes: every value's low byte, then
// every value's next byte, and so on (bytes of one significance together compress better).
inline uint32_t readPlanes(const uint8_t* run, size_t count, int bytes, size_t i) {
  uint32_t v = run[i];
  for (int b = 1; b < bytes; ++b) v |= uint32_t(run[b * count + i]) << (8 * b);
  return v;
}
inline void writePlanes(uint8_t* run, size_t count, int bytes, size_t i, uint32_t v) {
  for (int b = 0; b < bytes; ++b) run[b * count + i] = uint8_t(v >> (8 * b));
}

// Reads the packed form's values in sample order: the sums from their three channels' runs of
// differences, the squares from their residuals.
class PackedValues {
 public:
  PackedValues(const uint8_t* values, size_t coloured, size_t squared, int sum_bytes,
               int square_bytes)
      : values_(values),
        coloured_(coloured),
        squared_(squared),
        sum_bytes_(sum_bytes),
        square_bytes_(square_bytes) {}
  // The next coloured sample's sums.
  void nextSums(uint16_t sums[3]) {
    const size_t run = coloured_ * sum_bytes_;
    if (sum_bytes_ == 1) {  // modulo 2^8, as the sums fit a byte
      for (int c = 0; c < 3; ++c) sums[c] = last_[c] = uint8_t(last_[c] + values_[c * run + i_]);
    } else {
      for (int c = 0; c < 3; ++c) {
        last_[c] = uint16_t(last_[c] + readPlanes(values_ + c * run, coloured_, 2, i_));
        sums[c] = last_[c];
      }
    }
    ++i_;
  }
  // The square of the sample whose sums nextSums() gave last, seen by k >= 2 cameras.
  uint32_t nextSquare(const uint16_t sums[3], int k) {
    const uint8_t* run = values_ + 3 * coloured_ * sum_bytes_;
    return readPlanes(run, squared_, square_bytes_, q_++) + meanSquare(sums, k);
  }
  // Past the values: the edges.
  const uint8_t* end() const {
    return values_ + 3 * coloured_ * sum_bytes_ + squared_ * square_bytes_;
  }

 private:
  const uint8_t* values_;
  size_t coloured_, squared_;
  int sum_bytes_, square_bytes_;
  size_t i_ = 0, q_ = 0;  // the coloured and the squared samples read
  uint16_t last_[3] = {0, 0, 0};
};

}  // namespace

void encodeRefinementStatistics(const RefinementStatistics& stats, std::vector<uint8_t>& out) {
  const size_t n = stats.outside.size();
  uint32_t max_sum = 0, max_residual = 0;
  size_t coloured = 0, squared = 0, leaving = 0;
  forEachLeaving(stats.outside.data(), 0xff, n, stats.offset_count, [&](size_t) { ++leaving; });
  for (size_t s = 0; s < n; ++s) {
    if (stats.colour_count[s] == 0) continue;
    ++coloured;
    const uint16_t* v = &stats.sums[3 * s];
    max_sum = std::max({max_sum, uint32_t(v[0]), uint32_t(v[1]), uint32_t(v[2])});
    if (stats.colour_count[s] < 2) continue;
    ++squared;
    max_residual = std::max(
        max_residual, squareResidual(stats.squares[s], v, packedCount(stats.colour_count[s])));
  }
  const int sum_bytes = std::min(2, bytesFor(max_sum)), square_bytes = bytesFor(max_residual);
  const size_t values = kHeaderBytes + n, residuals = values + 3 * coloured * sum_bytes;
  const size_t contour_at = residuals + squared * square_bytes + leaving;
  out.resize(contour_at + contourBytes(uint64_t(stats.vertex_count)));
  size_t at = 0;
  put(out, at, uint32_t(stats.vertex_count), 4);
  out[at++] = uint8_t(stats.offset_count);
  out[at++] = uint8_t(stats.colour_bits);
  out[at++] = uint8_t(sum_bytes);
  out[at++] = uint8_t(square_bytes);
  for (size_t s = 0; s < n; ++s)
    out[at++] =
        uint8_t(std::min<int>(stats.outside[s], 15) | (packedCount(stats.colour_count[s]) << 4));
  uint32_t last[3] = {0, 0, 0};
  size_t i = 0, q = 0;  // the coloured and the squared samples written
  for (size_t s = 0; s < n; ++s) {
    if (stats.colour_count[s] == 0) continue;
    const uint16_t* v = &stats.sums[3 * s];
    for (int c = 0; c < 3; ++c) {  // modulo 2^(8 sum_bytes)
      writePlanes(&out[values + c * coloured * sum_bytes], coloured, sum_bytes, i, v[c] - last[c]);
      last[c] = v[c];
    }
    ++i;
    if (stats.colour_count[s] > 1) {
      writePlanes(&out[residuals], squared, square_bytes, q++,
                  squareResidual(stats.squares[s], v, packedCount(stats.colour_count[s])));
    }
  }
  at = residuals + squared * square_bytes;
  forEachLeaving(stats.outside.data(), 0xff, n, stats.offset_count,
                 [&](size_t s) { out[at++] = stats.edges[s]; });
  std::fill(out.begin() + contour_at, out.end(), 0);
  for (size_t v = 0; v < stats.contour.size(); ++v)
    if (stats.contour[v]) out[contour_at + v / 8] |= uint8_t(1 << (v % 8));
}

namespace {

// Why a buffer is refused.
Status refuse(std::string_view why) {
  return Status::failure("refinement statistics: " + std::string(why));
}

bool validWidths(int sum_bytes, int square_bytes) {
  return sum_bytes >= 1 && sum_bytes <= 2 && square_bytes >= 1 && square_bytes <= 4;
}

constexpr uint8_t kPackedOutside = 15;  // a packed count's outside count

// Whether the packed form after its header holds exactly the n samples' counts and the values
// they announce; the reason when not.
const char* checkBody(std::span<const uint8_t> data, size_t vertices, size_t n, int offsets,
                      int sum_bytes, int square_bytes, size_t& coloured, size_t& squared) {
  if (data.size() < kHeaderBytes + n) return "truncated counts";
  const uint8_t* counts = data.data() + kHeaderBytes;
  size_t with_colour = 0, with_square = 0;  // not the references: the counts' bytes may alias them
  for (size_t s = 0; s < n; ++s) {
    const int c = counts[s] >> 4;
    with_colour += c != 0, with_square += c > 1;
  }
  coloured = with_colour, squared = with_square;
  size_t leaving = 0;
  forEachLeaving(counts, kPackedOutside, n, offsets, [&](size_t) { ++leaving; });
  if (data.size() != kHeaderBytes + n + coloured * 3 * sum_bytes + squared * square_bytes +
                         leaving + contourBytes(vertices))
    return "size does not match its counts";
  // The contour's last byte holds no bits beyond the points.
  if (vertices % 8 != 0 && data.back() >> (vertices % 8) != 0)
    return "contour bits past its points";
  return nullptr;
}

Status decodePacked(std::span<const uint8_t> data, RefinementStatistics& out, int max_samples) {
  if (data.size() < kHeaderBytes) return refuse("shorter than its header");
  const uint32_t vertices = get(data.data(), 4);
  const int offsets = data[4], bits = data[5], sum_bytes = data[6], square_bytes = data[7];
  if (offsets == 0 || bits < 1 || bits > 8) return refuse("bad offset count or colour bits");
  if (!validWidths(sum_bytes, square_bytes)) return refuse("bad value widths");
  if (uint64_t(vertices) * offsets > uint64_t(max_samples)) return refuse("too many samples");
  const size_t n = size_t(vertices) * offsets;
  size_t coloured, squared;
  if (const char* why =
          checkBody(data, vertices, n, offsets, sum_bytes, square_bytes, coloured, squared))
    return refuse(why);
  const uint8_t* counts = data.data() + kHeaderBytes;
  out.reset(int(vertices), offsets, bits);
  PackedValues values(counts + n, coloured, squared, sum_bytes, square_bytes);
  for (size_t s = 0; s < n; ++s) {
    out.outside[s] = counts[s] & 15;
    const int k = out.colour_count[s] = counts[s] >> 4;
    if (k == 0) continue;
    uint16_t* sums = &out.sums[3 * s];
    values.nextSums(sums);
    // One camera: its colour is the sum.
    out.squares[s] = k == 1 ? sumOfSquares(sums) : values.nextSquare(sums, k);
  }
  const uint8_t* p = values.end();
  forEachLeaving(counts, kPackedOutside, n, offsets, [&](size_t s) { out.edges[s] = *p++; });
  for (size_t v = 0; v < vertices; ++v) out.contour[v] = (p[v / 8] >> (v % 8)) & 1;
  return {};
}

Status addPacked(std::span<const uint8_t> data, RefinementStatistics& sum) {
  if (data.size() < kHeaderBytes) return refuse("shorter than its header");
  const uint32_t vertices = get(data.data(), 4);
  const int offsets = data[4], bits = data[5], sum_bytes = data[6], square_bytes = data[7];
  if (int(vertices) != sum.vertex_count || offsets != sum.offset_count || bits != sum.colour_bits)
    return refuse("sizes differ from the mesh's");
  if (!validWidths(sum_bytes, square_bytes)) return refuse("bad value widths");
  const size_t n = size_t(vertices) * offsets;
  size_t coloured, squared;
  if (const char* why =
          checkBody(data, vertices, n, offsets, sum_bytes, square_bytes, coloured, squared))
    return refuse(why);
  const uint8_t* counts = data.data() + kHeaderBytes;
  PackedValues values(counts + n, coloured, squared, sum_bytes, square_bytes);
  for (size_t s = 0; s < n; ++s) {
    const int outside = counts[s] & 15, colour = counts[s] >> 4;
    if (outside) sum.outside[s] = uint8_t(std::min(255, sum.outside[s] + outside));
    if (colour == 0) continue;
    sum.colour_count[s] = uint8_t(std::min(255, sum.colour_count[s] + colour));
    uint16_t v[3];
    values.nextSums(v);
    for (int c = 0; c < 3; ++c) sum.sums[3 * s + c] = uint16_t(sum.sums[3 * s + c] + v[c]);
    sum.squares[s] += colour == 1 ? sumOfSquares(v) : values.nextSquare(v, colour);
  }
  const uint8_t* p = values.end();
  forEachLeaving(counts, kPackedOutside, n, offsets, [&](size_t s) {
    sum.edges[s] = RefinementStatistics::innerEdge(sum.edges[s], *p++);
  });
  for (size_t v = 0; v < vertices; ++v) sum.contour[v] |= (p[v / 8] >> (v % 8)) & 1;
  return {};
}

RefinementStatisticsCodec& threadCodec() {
  thread_local RefinementStatisticsCodec codec;
  return codec;
}

}  // namespace

static_assert(maxCompressedStatisticsBytes(100) ==
              kCompressedStatisticsHeaderBytes + ZSTD_COMPRESSBOUND(maxPackedStatisticsBytes(100)));
static_assert(maxCompressedStatisticsBytes(1 << 20) ==
              kCompressedStatisticsHeaderBytes +
                  ZSTD_COMPRESSBOUND(maxPackedStatisticsBytes(1 << 20)));

Status decodeRefinementStatistics(std::span<const uint8_t> data, RefinementStatistics& out,
                                  int max_samples) {
  if (isCompressedRefinementStatistics(data)) return threadCodec().decode(data, out, max_samples);
  return decodePacked(data, out, max_samples);
}

Status addEncodedRefinementStatistics(std::span<const uint8_t> data, RefinementStatistics& sum) {
  if (isCompressedRefinementStatistics(data)) return threadCodec().add(data, sum);
  return addPacked(data, sum);
}

void RefinementStatisticsCodec::ZstdFree::operator()(ZSTD_CCtx_s* c) const {
  ZSTD_freeCCtx(c);
}
void RefinementStatisticsCodec::ZstdFree::operator()(ZSTD_DCtx_s* d) const {
  ZSTD_freeDCtx(d);
}

RefinementStatisticsCodec::RefinementStatisticsCodec() = default;
RefinementStatisticsCodec::~RefinementStatisticsCodec() = default;
RefinementStatisticsCodec::RefinementStatisticsCodec(RefinementStatisticsCodec&&) noexcept =
    default;
RefinementStatisticsCodec& RefinementStatisticsCodec::operator=(
    RefinementStatisticsCodec&&) noexcept = default;

void RefinementStatisticsCodec::encode(const RefinementStatistics& stats,
                                       std::vector<uint8_t>& out) {
  encodeRefinementStatistics(stats, packed_);
  if (!compressor_) {
    compressor_.reset(ZSTD_createCCtx());
    if (compressor_ &&
        (ZSTD_isError(
             ZSTD_CCtx_setParameter(compressor_.get(), ZSTD_c_compressionLevel, kZstdLevel)) ||
         ZSTD_isError(ZSTD_CCtx_setParameter(compressor_.get(), ZSTD_c_hashLog, kZstdHashLog)) ||
         ZSTD_isError(ZSTD_CCtx_setParameter(compressor_.get(), ZSTD_c_checksumFlag, 1)))) {
      compressor_.reset();
    }
  }
  constexpr size_t h = kCompressedStatisticsHeaderBytes;
  out.resize(h + ZSTD_compressBound(packed_.size()));
  const size_t size = compressor_ ? ZSTD_compress2(compressor_.get(), out.data() + h,
                                                   out.size() - h, packed_.data(), packed_.size())
                                  : 0;
  if (!compressor_ || ZSTD_isError(size)) {
    out.assign(packed_.begin(), packed_.end());
    return;
  }
  out.resize(h + size);
  std::copy_n(packed_.begin(), 6, out.begin());  // vertices, offsets, colour bits
  out[6] = 0;
  out[7] = kZstdCompression;
  size_t at = 8;
  put(out, at, uint32_t(packed_.size()), 4);
}

Status RefinementStatisticsCodec::unpack(std::span<const uint8_t> data, int max_samples,
                                         std::span<const uint8_t>& packed) {
  if (!isCompressedRefinementStatistics(data)) {
    packed = data;
    return {};
  }
  constexpr size_t h = kCompressedStatisticsHeaderBytes;
  if (data.size() < h) return refuse("shorter than its compressed header");
  if (data[7] != kZstdCompression) return refuse("unknown compression " + std::to_string(data[7]));
  const uint64_t points = get(data.data(), 4), n = points * data[4];
  if (n > uint64_t(max_samples)) return refuse("too many samples");
  const uint64_t size = get(data.data() + 8, 4), least = kHeaderBytes + n + contourBytes(points);
  if (size < least || size > maxPackedStatisticsBytes(n)) {
    return refuse("compressed form declares " + std::to_string(size) + " packed bytes, " +
                  std::to_string(n) + " samples take " + std::to_string(least) + " to " +
                  std::to_string(maxPackedStatisticsBytes(n)));
  }
  const std::span<const uint8_t> frame = data.subspan(h);
  // Only a plain zstd frame: no skippable or legacy frames, no concatenation.
  if (frame.size() < 4 || get(frame.data(), 4) != ZSTD_MAGICNUMBER)
    return refuse("compressed form does not hold a zstd frame");
  const unsigned long long content = ZSTD_getFrameContentSize(frame.data(), frame.size());
  if (content == ZSTD_CONTENTSIZE_ERROR) return refuse("malformed or truncated zstd frame header");
  if (content == ZSTD_CONTENTSIZE_UNKNOWN) return refuse("zstd frame does not declare its size");
  if (content != size) {
    return refuse("zstd frame declares " + std::to_string(content) + " bytes, the header " +
                  std::to_string(size));
  }
  const size_t frame_size = ZSTD_findFrameCompressedSize(frame.data(), frame.size());
  if (ZSTD_isError(frame_size))
    return refuse("truncated zstd frame: " + std::string(ZSTD_getErrorName(frame_size)));
  if (frame_size != frame.size()) return refuse("bytes after the zstd frame");
  if (!decompressor_) {
    decompressor_.reset(ZSTD_createDCtx());
    if (!decompressor_) return refuse("out of memory for a zstd context");
  }
  packed_.resize(size);
  const size_t got = ZSTD_decompressDCtx(decompressor_.get(), packed_.data(), packed_.size(),
                                         frame.data(), frame.size());
  if (ZSTD_isError(got))
    return refuse("corrupt zstd frame: " + std::string(ZSTD_getErrorName(got)));
  if (got != size) {
    return refuse("zstd frame holds " + std::to_string(got) + " bytes, the header says " +
                  std::to_string(size));
  }
  if (!std::equal(data.begin(), data.begin() + 6, packed_.begin()))
    return refuse("the packed header differs from the compressed one");
  packed = packed_;
  return {};
}

Status RefinementStatisticsCodec::decode(std::span<const uint8_t> data, RefinementStatistics& out,
                                         int max_samples) {
  std::span<const uint8_t> packed;
  Status unpacked = unpack(data, max_samples, packed);
  return unpacked.ok() ? decodePacked(packed, out, max_samples) : unpacked;
}

Status RefinementStatisticsCodec::add(std::span<const uint8_t> data, RefinementStatistics& sum) {
  // Both forms start with the sizes: another mesh's statistics are refused before decompressing.
  if (data.size() >= kHeaderBytes && (int(get(data.data(), 4)) != sum.vertex_count ||
                                      data[4] != sum.offset_count || data[5] != sum.colour_bits))
    return refuse("sizes differ from the mesh's");
  std::span<const uint8_t> packed;
  Status unpacked = unpack(data, sum.sampleCount(), packed);
  return unpacked.ok() ? addPacked(packed, sum) : unpacked;
}

}  // namespace lumistage
