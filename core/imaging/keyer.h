#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
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
// two G, B), the last column or row of an odd-sized mosaic from the cell before it; Mono8 as grey.
// Bayer images are at least 2x2.
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
      // A cell a pair of columns and rows: an odd width's or height's last pixel has no pair of its
      // own (read past the row, or past the image, before).
      const size_t x0 = std::min(size_t(x), size_t(image.width - 2)) & ~size_t(1),
                   y0 = std::min(size_t(y), size_t(image.height - 2)) & ~size_t(1);
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
  bool isForeground(const Rgb& c, int x, int y) const {
    return isForegroundLevel(float(greenExcess(c)), x, y);
  }
  // How much the pixel (x, y), of colour `c`, looks like the screen: its green excess. A pixel that
  // the actor covers in part mixes the two colours, so this is nearly linear in the screen's share
  // of the pixel, and a silhouette's edge lies where it is halfway between the actor's and the
  // screen's.
  int backgroundLevel(const Rgb& c, int /*x*/, int /*y*/) const { return greenExcess(c); }
  // Whether a background level (interpolated between pixels, say) near pixel (x, y) is the
  // actor's: isForeground() of a colour is this of its level.
  bool isForegroundLevel(float level, int /*x*/, int /*y*/) const {
    return level < float(threshold_);
  }
  // Whether the level is the actor's with a margin: under `purity` (in (0, 1]) times the
  // threshold, where a pixel the screen covers in part (more of its green excess) is not.
  bool isPureForegroundLevel(float level, int /*x*/, int /*y*/, float purity) const {
    return level < purity * float(threshold_);
  }
  static int greenExcess(const Rgb& c) { return c.g - (c.r > c.b ? c.r : c.b); }
  // Learns from a frame of the empty stage, or of the stage with the actor (a person rarely fills
  // the view): sets the threshold at three quarters of the 1st percentile of the screen's green
  // excess, and at least `minimum`. The screen's samples: those whose excess is at least a third of
  // the median's (of the samples with any excess), and kMinScreenSampleExcess. Returns the
  // threshold. At half of it, the actor's edges that the screen's green light spills on (dark hair,
  // skin at a grazing angle) fell below it: 0.64% of the reference actor's pixels keyed as screen,
  // against 0.10% now, none of the screen keyed as the actor either way.
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
  static constexpr int kMinScreenSampleExcess = 8;  // a grey's noise stays below
  // Follows `measured`, the same screen learnt again from a later frame: takes its threshold when
  // its darkest excess moved from the learnt one by more than an eighth (and kFollowLevels), so
  // that a screen whose lights dimmed since it was learnt is not keyed as the actor (its darkest
  // parts fall below a threshold three quarters of what they were), and a brighter one keys the
  // spill on the actor's edges again; the few levels a frame's noise and the actor's moving
  // shadow shift it by leave the key as it is. A measurement that saw no screen changes nothing.
  // Returns whether the key changed.
  bool follow(const GreenScreenKeyer& measured);
  // Whether follow(measured) would change the key.
  bool differs(const GreenScreenKeyer& measured) const;
  static constexpr int kFollowLevels = 4;

 private:
  int threshold_;
  int screen_excess_ = 0;
};

// For stages that are not green: a clean plate, the empty stage learnt per pixel from frames of
// it (a session's plate/, filmed before the take): each pixel's mean colour and its spread over
// the frames. A pixel is the actor when its colour lies further from the plate's than the pixel's
// bound: `k` spreads (the sensor's noise), and at least kFloorLevels. Shadows are not told from
// the actor: the actor's shadow on the floor keys as the actor (the plate's colour dimmed counted
// as the plate cost the virtual studio's room, which casts none, 7 mm of MPJPE:
// docs/figures-history.md).
class BackgroundModel {
 public:
  // Throws Error unless the sizes are positive and k > 0.
  BackgroundModel(int width, int height, float k = 4.0f);
  // Adds a frame of the empty stage; call learn() after the last, and key only after it. Throws
  // Error, naming both sizes, for a frame of another size than the model's, and for a frame added
  // after learn(); learn() does without a frame.
  void add(const ImageView& empty);
  void learn();
  bool learnt() const { return !plate_.empty(); }
  bool isForeground(const ImageView& image, int x, int y) const {
    return isForeground(colourAt(image, x, y), x, y);
  }
  // The same for the colour `c` already read at (x, y).
  bool isForeground(const Rgb& c, int x, int y) const {
    const Texel& t = plate_[pixelOf(x, y)];
    return distance2(c, t) > bound2(t);
  }
  // How much the pixel (x, y), of colour `c`, looks like the empty stage: minus its colour's
  // distance from the plate's, which is linear in the actor's share of the pixel
  // (GreenScreenKeyer::backgroundLevel).
  float backgroundLevel(const Rgb& c, int x, int y) const {
    return -std::sqrt(distance2(c, plate_[pixelOf(x, y)]));
  }
  // Whether a background level (interpolated between pixels, say) near pixel (x, y) is the
  // actor's, by the pixel's bound: isForeground() of a colour is this of its level.
  bool isForegroundLevel(float level, int x, int y) const {
    return level < 0 && level * level > bound2(plate_[pixelOf(x, y)]);
  }
  // Whether the level is the actor's with a margin: its distance from the empty stage over the
  // pixel's bound divided by `purity` (in (0, 1]), which a pixel the stage shows through in part
  // does not reach (GreenScreenKeyer::isPureForegroundLevel).
  bool isPureForegroundLevel(float level, int x, int y, float purity) const {
    return level < 0 && purity * purity * level * level > bound2(plate_[pixelOf(x, y)]);
  }
  int frames() const { return frames_; }
  static constexpr float kFloorLevels = 12.0f;  // a bound above the noise of a few levels

 private:
  size_t pixelOf(int x, int y) const {
    return size_t(std::clamp(y, 0, height_ - 1)) * width_ + size_t(std::clamp(x, 0, width_ - 1));
  }
  // A pixel of the plate: its mean colour (rounded) and its bound, in one word, so that keying a
  // cell reads one cache line of the plate (a third of the time with floats, and a quarter of the
  // memory).
  struct Texel {
    uint8_t r, g, b, bound;
  };
  static int distance2(const Rgb& c, const Texel& t) {
    const int dr = c.r - t.r, dg = c.g - t.g, db = c.b - t.b;
    return dr * dr + dg * dg + db * db;
  }
  static int bound2(const Texel& t) { return int(t.bound) * t.bound; }

  int width_, height_;
  float k_;
  int frames_ = 0;
  std::vector<float> sum_, sum2_;  // per pixel and channel, while adding
  std::vector<Texel> plate_;
};

// Every rig camera's clean plate, nullptr for a camera without one (keyed on its green screen, or
// from masks).
using CameraPlates = std::vector<std::shared_ptr<const BackgroundModel>>;

// For footage without a screen to key, segmented by another tool (a matting tool, a segmenter):
// the frame's mask of the actor (one byte a pixel, non-zero on the actor, the image's size) as a
// key whose background level depends on the position only: -1 on the actor, +1 off it. Levels
// interpolated between pixels then cross the bound (0) half a pixel beyond the actor's last pixel,
// on the pixels' border: the sampler's sub-pixel edge (RefinementSampler) lies on the mask's edge.
// On a Bayer image, whose colour is its 2x2 cell's (colourAt), a pixel's level is its cell's mean.
// A view of the mask, which must outlive the key; made afresh per frame, it allocates nothing.
class MaskKey {
 public:
  MaskKey() = default;
  // `cells`: the image is Bayer (levels of 2x2 cells). Sizes of at least 2x2 for cells.
  MaskKey(const uint8_t* mask, int width, int height, bool cells = false)
      : mask_(mask), width_(width), height_(height), cells_(cells) {}

  bool isForeground(const ImageView& /*image*/, int x, int y) const { return level(x, y) < 0.0f; }
  bool isForeground(const Rgb& /*c*/, int x, int y) const { return level(x, y) < 0.0f; }
  // The pixel's level, whatever its colour: GreenScreenKeyer::backgroundLevel's counterpart.
  float backgroundLevel(const Rgb& /*c*/, int x, int y) const { return level(x, y); }
  bool isForegroundLevel(float level, int /*x*/, int /*y*/) const { return level < 0.0f; }
  // A level the background takes less than `purity` / 2 of (the actor's level is -1, the
  // background's +1): under purity x the bound, as a green key's (GreenScreenKeyer).
  bool isPureForegroundLevel(float level, int /*x*/, int /*y*/, float purity) const {
    return level < purity - 1.0f;
  }
  // -1 on the actor, +1 off it (a cell's mean on Bayer); +1 beyond the mask.
  float level(int x, int y) const {
    if (x < 0 || y < 0 || x >= width_ || y >= height_) return 1.0f;
    if (!cells_) return mask_[size_t(y) * width_ + x] ? -1.0f : 1.0f;
    // The cell that holds the pixel, as colourAt reads it (an odd size's last column or row: the
    // cell before it).
    const size_t x0 = std::min(size_t(x), size_t(width_ - 2)) & ~size_t(1),
                 y0 = std::min(size_t(y), size_t(height_ - 2)) & ~size_t(1);
    const uint8_t* p = mask_ + y0 * width_ + x0;
    const int actor = (p[0] != 0) + (p[1] != 0) + (p[width_] != 0) + (p[width_ + 1] != 0);
    return 1.0f - 0.5f * float(actor);
  }
  const uint8_t* mask() const { return mask_; }

 private:
  const uint8_t* mask_ = nullptr;
  int width_ = 0, height_ = 0;
  bool cells_ = false;
};

// The mean colour of the 3x3 pixels around (x, y), those beyond the image's edge left out. On
// Bayer the window's pixels lie in at most 2x2 cells: each cell's colour is read once, weighted by
// how many of the window's pixels it holds.
inline Rgb meanColourAround(const ImageView& image, int x, int y) {
  const int x0 = std::max(0, x - 1), x1 = std::min(image.width - 1, x + 1);
  const int y0 = std::max(0, y - 1), y1 = std::min(image.height - 1, y + 1);
  const int n = (x1 - x0 + 1) * (y1 - y0 + 1);
  Rgb sum;
  auto add = [&](int px, int py, int weight) {
    const Rgb c = colourAt(image, px, py);
    sum.r += weight * c.r, sum.g += weight * c.g, sum.b += weight * c.b;
  };
  if (isBayer(image.format)) {
    // Pixels a..b: those in a's cell (from a) and those in the next (from `split`, maybe none).
    auto cells = [](int a, int b, int first[2], int count[2]) {
      const int split = std::min(b, a | 1) + 1;
      first[0] = a, count[0] = split - a;
      first[1] = split, count[1] = b - split + 1;
    };
    int fx[2], wx[2], fy[2], wy[2];
    cells(x0, x1, fx, wx);
    cells(y0, y1, fy, wy);
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i)
        if (wx[i] > 0 && wy[j] > 0) add(fx[i], fy[j], wx[i] * wy[j]);
  } else {
    for (int yy = y0; yy <= y1; ++yy)
      for (int xx = x0; xx <= x1; ++xx) add(xx, yy, 1);
  }
  return {(sum.r + n / 2) / n, (sum.g + n / 2) / n, (sum.b + n / 2) / n};
}

// Whether the `step` x `step` cell (cx, cy) of a low-resolution silhouette shows the actor: the
// key of the mean colour of the 3x3 pixels around the cell's centre pixel. One pixel's key is at
// the mercy of its sensor noise and of the spill on an edge that crosses it; the mean keys the
// cell by what covers its middle. MPJPE on the reference clips 18.9 / 25.7 / 20.6 / 20.9 mm with
// the centre pixel alone -> 15.2 / 20.1 / 14.9 / 16.8 mm (docs/eval-report.md).
template <typename Key>
bool keyCell(const Key& key, const ImageView& image, int cx, int cy, int step) {
  const int x = cx * step + step / 2, y = cy * step + step / 2;
  return key.isForeground(meanColourAround(image, x, y), x, y);
}

// A low-resolution silhouette: every `step` x `step` cell keyed (keyCell), one byte a cell (255
// actor). `mask` is resized only when its size differs.
template <typename Key>
void lowResSilhouette(const Key& key, const ImageView& image, int step,
                      std::vector<uint8_t>& mask) {
  const int w = image.width / step, h = image.height / step;
  if (mask.size() != size_t(w) * h) mask.resize(size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) mask[size_t(y) * w + x] = keyCell(key, image, x, y, step) ? 255 : 0;
}

}  // namespace lumistage
