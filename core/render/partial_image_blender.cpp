#include "core/render/partial_image_blender.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/imaging/partial_image_codec.h"
#include "core/render/silhouette_feather.h"

namespace lumistage {

namespace {

// The alpha bytes' shares (shareOfAlpha).
struct ShareWeights {
  ShareWeights() {
    for (int a = 0; a < 256; ++a) weight[a] = float(shareOfAlpha(uint8_t(a)));
  }
  float weight[256];
};
const ShareWeights kShareWeights;

}  // namespace

double shareOfAlpha(uint8_t alpha) {
  return alpha == 0 ? 0.0 : std::exp2((double(alpha) - 255.0) / kAlphaStepsPerOctave);
}

void PartialImageBlender::reset(int width, int height) {
  added_ = 0;
  if (width == width_ && height == height_ && !sums_.empty()) {
    for (int y = 0; y < height_; ++y) {
      if (row_begin_[y] < row_end_[y]) {
        float* row = sums_.data() + (size_t(y) * width_ + row_begin_[y]) * 4;
        std::fill(row, row + size_t(row_end_[y] - row_begin_[y]) * 4, 0.0f);
      }
    }
  } else {
    width_ = width;
    height_ = height;
    sums_.assign(size_t(width) * height * 4, 0.0f);
    row_begin_.resize(height);
    row_end_.resize(height);
  }
  std::fill(row_begin_.begin(), row_begin_.end(), width_);
  std::fill(row_end_.begin(), row_end_.end(), 0);
}

void PartialImageBlender::accumulate(size_t first, const uint8_t* p, size_t count) {
  while (count > 0) {
    const int y = int(first / width_), x = int(first % width_);
    const int n = int(std::min<size_t>(count, size_t(width_ - x)));
    float* s = sums_.data() + first * 4;
    int begin = width_, end = 0;
    for (int i = 0; i < n; ++i, s += 4, p += 4) {
      if (p[3] == 0) continue;
      const float a = kShareWeights.weight[p[3]];
      s[0] += a * p[0];
      s[1] += a * p[1];
      s[2] += a * p[2];
      s[3] += a;
      begin = std::min(begin, x + i);
      end = x + i + 1;
    }
    row_begin_[y] = std::min(row_begin_[y], begin);
    row_end_[y] = std::max(row_end_[y], end);
    first += n;
    count -= n;
  }
}

bool PartialImageBlender::add(std::span<const uint8_t> rgba) {
  const size_t pixels = size_t(width_) * height_;
  if (rgba.size() != pixels * 4) return false;
  accumulate(0, rgba.data(), pixels);
  ++added_;
  return true;
}

bool PartialImageBlender::addAlphaRuns(std::span<const uint8_t> encoded) {
  const bool valid = forEachLiteralRun(
      encoded, size_t(width_) * height_,
      [this](size_t first, const uint8_t* rgba, size_t count) { accumulate(first, rgba, count); });
  added_ += valid;
  return valid;
}

void PartialImageBlender::finish(std::vector<uint8_t>& rgba) const {
  const size_t pixels = size_t(width_) * height_;
  if (rgba.size() != pixels * 4) rgba.resize(pixels * 4);
  for (int y = 0; y < height_; ++y) {
    uint8_t* row = rgba.data() + size_t(y) * width_ * 4;
    const int begin = std::min(row_begin_[y], width_), end = std::max(row_end_[y], begin);
    std::memset(row, 0, size_t(begin) * 4);
    const float* s = sums_.data() + (size_t(y) * width_ + begin) * 4;
    uint8_t* out = row + size_t(begin) * 4;
    for (int x = begin; x < end; ++x, s += 4, out += 4) {
      const float a = s[3];
      if (a == 0) {
        out[0] = out[1] = out[2] = out[3] = 0;
        continue;
      }
      const float inverse = 1.0f / a;
      for (int k = 0; k < 3; ++k)
        out[k] = static_cast<uint8_t>(std::min(255.0f, s[k] * inverse + 0.5f));
      out[3] = 255;
    }
    std::memset(out, 0, size_t(width_ - end) * 4);
  }
  featherSilhouette(rgba, width_, height_, row_begin_, row_end_);
}

}  // namespace lumistage
