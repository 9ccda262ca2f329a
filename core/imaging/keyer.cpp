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

int checkedSize(int width, int height, float k) {
  if (width <= 0 || height <= 0 || !(k > 0)) {
    throw Error(
        fmt::format("background model: {}x{} pixels, k {}: expected positive sizes and k > 0",
                    width, height, k));
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

BackgroundModel::BackgroundModel(int width, int height, float k)
    : width_(checkedSize(width, height, k)),
      height_(height),
      k_(k),
      sum_(size_t(width) * height * 3, 0.0f),
      sum2_(size_t(width) * height * 3, 0.0f) {}

void BackgroundModel::add(const ImageView& empty) {
  if (learnt()) throw Error("background model: a frame added after learning");
  if (empty.width != width_ || empty.height != height_ || empty.data == nullptr) {
    throw Error(fmt::format("background model of {}x{} pixels: an empty stage's frame of {}x{}",
                            width_, height_, empty.width, empty.height));
  }
  for (int y = 0; y < height_; ++y) {
    float* sum = &sum_[3 * size_t(y) * width_];
    float* sum2 = &sum2_[3 * size_t(y) * width_];
    for (int x = 0; x < width_; ++x) {
      const Rgb c = colourAt(empty, x, y);
      const float v[3] = {float(c.r), float(c.g), float(c.b)};
      for (int k = 0; k < 3; ++k) {
        sum[3 * x + k] += v[k];
        sum2[3 * x + k] += v[k] * v[k];
      }
    }
  }
  ++frames_;
}

void BackgroundModel::learn() {
  if (frames_ == 0) throw Error("background model: no frame of the empty stage to learn from");
  const size_t pixels = size_t(width_) * height_;
  plate_.resize(pixels);
  const float n = float(frames_);
  for (size_t p = 0; p < pixels; ++p) {
    float variance = 0;
    uint8_t mean[3];
    for (int k = 0; k < 3; ++k) {
      const float m = sum_[3 * p + k] / n;
      mean[k] = uint8_t(std::lround(std::clamp(m, 0.0f, 255.0f)));
      variance += std::max(0.0f, sum2_[3 * p + k] / n - m * m);
    }
    const float bound = std::max(k_ * std::sqrt(variance), kFloorLevels);
    plate_[p] = {mean[0], mean[1], mean[2], uint8_t(std::min(255.0f, std::ceil(bound)))};
  }
  // The sums are done with: the plate keeps its means and bounds only.
  sum_ = {};
  sum2_ = {};
}

}  // namespace lumistage
