#pragma once

#include <cstdint>
#include <vector>

#include "core/capture/image.h"

namespace lumistage {

// Segmentation on demand: whether one pixel shows the actor, computed from that pixel alone (and
// the camera's background statistics), so that a step pays only for the pixels it asks about —
// the paper's point. Works on the camera's own pixels: Bayer is read in its 2x2 cell, never
// demosaiced as a whole.

struct Rgb {
  int r = 0, g = 0, b = 0;
};

// The colour at a pixel: RGB8 directly; Bayer from the 2x2 cell that holds it (R, the mean of the
// two G, B); Mono8 as grey.
inline Rgb colourAt(const ImageView& image, int x, int y) {
  const uint8_t* p = image.data;
  switch (image.format) {
    case PixelFormat::kRgb8: {
      const uint8_t* q = p + 3 * (size_t(y) * image.width + x);
      return {q[0], q[1], q[2]};
    }
    case PixelFormat::kBayerRggb8:
    case PixelFormat::kBayerGrbg8:
    case PixelFormat::kBayerGbrg8:
    case PixelFormat::kBayerBggr8: {
      const BayerLayout l = bayerLayout(image.format);
      const size_t x0 = size_t(x) & ~size_t(1), y0 = size_t(y) & ~size_t(1);
      const uint8_t* cell = p + y0 * image.width + x0;
      const size_t w = image.width;
      const int red = cell[l.red_y * w + l.red_x], blue = cell[(1 - l.red_y) * w + 1 - l.red_x];
      const int green =
          (cell[l.red_y * w + 1 - l.red_x] + cell[(1 - l.red_y) * w + l.red_x] + 1) / 2;
      return {red, green, blue};
    }
    case PixelFormat::kMono8:
      break;
  }
  const int v = p[size_t(y) * image.width + x];
  return {v, v, v};
}

// Green-screen keying by the green excess e = g - max(r, b): the screen has a large one (under
// any of its lighting), people, clothes and skin a small or negative one, green spill on the
// actor's edges a moderate one. A pixel is background when e exceeds a threshold learned from
// the camera's own view of the screen: learnScreen() on pixels known (or very likely) to be
// screen sets it below the screen's darkest, most spilled parts.
class GreenScreenKeyer {
 public:
  explicit GreenScreenKeyer(int threshold = 30) : threshold_(threshold) {}

  bool isForeground(const ImageView& image, int x, int y) const {
    return isForeground(colourAt(image, x, y), x, y);
  }
  // The same for the colour `c` already read at (x, y).
  bool isForeground(const Rgb& c, int /*x*/, int /*y*/) const {
    return greenExcess(c) < threshold_;
  }
  // How much the pixel looks like the screen: its green excess. A pixel that the actor covers in
  // part mixes the two colours, so this is nearly linear in the screen's share of the pixel, and a
  // silhouette's edge lies where it is halfway between the actor's and the screen's.
  int backgroundLevel(const ImageView& image, int x, int y) const {
    return greenExcess(colourAt(image, x, y));
  }
  static int greenExcess(const Rgb& c) { return c.g - (c.r > c.b ? c.r : c.b); }
  // Learns from a frame of the empty stage, or of the stage with the actor (a person rarely fills
  // the view): sets the threshold at three quarters of the 1st percentile of the screen's green
  // excess, and at least `minimum`. Returns the threshold. At half of it, the actor's edges that
  // the screen's green light spills on (dark hair, skin at a grazing angle) fell below it: 0.64%
  // of the reference actor's pixels keyed as screen, against 0.10% now, none of the screen keyed
  // as the actor either way.
  int learnScreen(const ImageView& screen, int step = 8, int minimum = 12);
  int threshold() const { return threshold_; }
  // The learnt screen's darkest green excess (its 1st percentile, 8-bit levels); 0 before
  // learning, or when learnScreen() saw no green at all (the threshold then stays as it was).
  int screenExcess() const { return screen_excess_; }
  // Below this darkest excess the screen is too dim to key cleanly: the reference studio's screen
  // lit at 0.43 of its brightness (darkest excess 26 levels) lost 1.7% of the actor's pixels to
  // the key and the tracker lost the actor (MPJPE over 400 mm); lit as it is (65 levels), 0.1%,
  // and tracked.
  static constexpr int kDimScreenExcess = 40;

 private:
  int threshold_;
  int screen_excess_ = 0;
};

// For stages that are not green: a background model learned from frames of the empty stage, per
// block of block x block pixels: the mean colour and its spread. A pixel whose colour is further
// from its block's mean than `k` spreads (and than a floor of a few levels, for noise) is the
// actor.
class BackgroundModel {
 public:
  BackgroundModel(int width, int height, int block = 8, float k = 4.0f);
  // Adds a frame of the empty stage; call learn() after the last.
  void add(const ImageView& empty);
  void learn();
  bool isForeground(const ImageView& image, int x, int y) const {
    return isForeground(colourAt(image, x, y), x, y);
  }
  // The same for the colour `c` already read at (x, y).
  bool isForeground(const Rgb& c, int x, int y) const;
  // How much the pixel looks like the empty stage: minus its colour's distance from its block's
  // mean, which is linear in the actor's share of the pixel (GreenScreenKeyer::backgroundLevel).
  float backgroundLevel(const ImageView& image, int x, int y) const;
  int frames() const { return frames_; }

 private:
  size_t blockOf(int x, int y) const { return size_t(y / block_) * columns_ + x / block_; }
  // The squared distance of `c` from block b's mean colour.
  float distance2(const Rgb& c, size_t b) const;

  int width_, height_, block_, columns_, rows_;
  float k_;
  int frames_ = 0;
  std::vector<double> sum_, sum2_;    // per block and channel, while adding
  std::vector<float> mean_, limit2_;  // per block: mean colour, squared distance limit
};

// A low-resolution silhouette: the key evaluated at the centre of every `step` x `step` cell,
// one byte a cell (255 actor). `mask` is resized only when its size differs.
template <typename Key>
void lowResSilhouette(const Key& key, const ImageView& image, int step,
                      std::vector<uint8_t>& mask) {
  const int w = image.width / step, h = image.height / step;
  if (mask.size() != size_t(w) * h) mask.resize(size_t(w) * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      mask[size_t(y) * w + x] =
          key.isForeground(image, x * step + step / 2, y * step + step / 2) ? 255 : 0;
    }
  }
}

}  // namespace lumistage
