#include "core/imaging/keyer.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "core/base/error.h"

namespace lumistage {

int GreenScreenKeyer::learnScreen(const ImageView& screen, int step, int minimum) {
  std::vector<int> excess;
  for (int y = step / 2; y < screen.height; y += step) {
    for (int x = step / 2; x < screen.width; x += step) {
      const Rgb c = colourAt(screen, x, y);
      const int e = greenExcess(c);
      if (e > 0) excess.push_back(e);  // what is not green at all is not screen
    }
  }
  if (excess.empty()) {
    screen_excess_ = 0;
    return threshold_;
  }
  // The screen is most of the view: its samples are those near the median's excess or above.
  // Neutral things in view (a black suit, grey truss, an unlit floor) have an excess of a few
  // levels from noise; more than a percent of the view of them held the 1st percentile, and the
  // threshold fell to its minimum (the screen "too dim", the actor's edges keyed as screen).
  const size_t middle = excess.size() / 2;
  std::nth_element(excess.begin(), excess.begin() + middle, excess.end());
  const int least = std::max(kMinScreenSampleExcess, excess[middle] / 3);
  std::erase_if(excess, [&](int e) { return e < least; });
  if (excess.empty()) {  // nothing green enough to be a screen (lights off, a lens cap)
    screen_excess_ = 0;
    return threshold_;
  }
  const size_t at = excess.size() / 100;
  std::nth_element(excess.begin(), excess.begin() + at, excess.end());
  screen_excess_ = excess[at];
  threshold_ = std::max(minimum, 3 * excess[at] / 4);
  return threshold_;
}

namespace {

int checkedSize(int width, int height, int block) {
  if (width <= 0 || height <= 0 || block <= 0) {
    throw Error(fmt::format("background model: {}x{} pixels in blocks of {}: all must be positive",
                            width, height, block));
  }
  return width;
}

}  // namespace

bool GreenScreenKeyer::differs(const GreenScreenKeyer& measured) const {
  const int now = measured.screen_excess_;
  return now > 0 && (screen_excess_ == 0 ||
                     std::abs(now - screen_excess_) > std::max(kFollowLevels, screen_excess_ / 8));
}

bool GreenScreenKeyer::follow(const GreenScreenKeyer& measured) {
  if (!differs(measured)) return false;
  const int now = measured.screen_excess_;
  threshold_ = measured.threshold_;
  screen_excess_ = now;
  return true;
}

BackgroundModel::BackgroundModel(int width, int height, int block, float k)
    : width_(checkedSize(width, height, block)),
      height_(height),
      block_(block),
      columns_((width + block - 1) / block),
      rows_((height + block - 1) / block),
      k_(k),
      sum_(size_t(columns_) * rows_ * 3, 0.0),
      sum2_(size_t(columns_) * rows_ * 3, 0.0) {}

void BackgroundModel::add(const ImageView& empty) {
  if (empty.width != width_ || empty.height != height_ || empty.data == nullptr) {
    throw Error(fmt::format("background model of {}x{} pixels: an empty stage's frame of {}x{}",
                            width_, height_, empty.width, empty.height));
  }
  // Sample a few pixels per block: the spread of a block includes its texture and the noise.
  for (int y = 0; y < height_; y += 2) {
    for (int x = 0; x < width_; x += 2) {
      const Rgb c = colourAt(empty, x, y);
      const size_t b = 3 * (size_t(y / block_) * columns_ + x / block_);
      const double v[3] = {double(c.r), double(c.g), double(c.b)};
      for (int k = 0; k < 3; ++k) {
        sum_[b + k] += v[k];
        sum2_[b + k] += v[k] * v[k];
      }
    }
  }
  ++frames_;
}

void BackgroundModel::learn() {
  if (frames_ == 0) throw Error("background model: no frame of the empty stage to learn from");
  const size_t blocks = size_t(columns_) * rows_;
  mean_.assign(blocks * 3, 0.0f);
  limit2_.assign(blocks, 0.0f);
  for (size_t b = 0; b < blocks; ++b) {
    const int bx = int(b % columns_), by = int(b / columns_);
    const int w = std::min(block_, width_ - bx * block_),
              h = std::min(block_, height_ - by * block_);
    const double n = std::max(1.0, double(frames_) * ((w + 1) / 2) * ((h + 1) / 2));
    double variance = 0;
    for (int k = 0; k < 3; ++k) {
      const double mean = sum_[3 * b + k] / n;
      mean_[3 * b + k] = float(mean);
      variance += std::max(0.0, sum2_[3 * b + k] / n - mean * mean);
    }
    const float spread = float(std::sqrt(variance));
    const float limit = std::max(k_ * spread, 12.0f);
    limit2_[b] = limit * limit;
  }
}

float BackgroundModel::distance2(const Rgb& c, size_t b) const {
  const float dr = c.r - mean_[3 * b], dg = c.g - mean_[3 * b + 1], db = c.b - mean_[3 * b + 2];
  return dr * dr + dg * dg + db * db;
}

bool BackgroundModel::isForeground(const Rgb& c, int x, int y) const {
  const size_t b = blockOf(x, y);
  return distance2(c, b) > limit2_[b];
}

float BackgroundModel::backgroundLevel(const Rgb& c, int x, int y) const {
  return -std::sqrt(distance2(c, blockOf(x, y)));
}

bool BackgroundModel::isForegroundLevel(float level, int x, int y) const {
  return level < 0 && level * level > limit2_[blockOf(x, y)];
}

bool BackgroundModel::isPureForegroundLevel(float level, int x, int y, float purity) const {
  return level < 0 && purity * purity * level * level > limit2_[blockOf(x, y)];
}

}  // namespace lumistage
