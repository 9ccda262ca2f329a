#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace lumistage {

// A partial image's alpha byte: 0 where the node drew nothing, else the node's share of the
// lumigraph weight (LumigraphRenderer) on a logarithmic scale, kAlphaStepsPerOctave steps an
// octave: share = 2^((alpha - 255) / 16), 255 a share of 1, each step 4.4% less, 1 the least
// (2^-15.9). The shares that the misregistration's factor leaves where every camera sees an edge
// are a few thousandths; linear bytes rounded their proportions to a level or two of 255.
inline constexpr double kAlphaStepsPerOctave = 16;
double shareOfAlpha(uint8_t alpha);

// The studio's side of distributed lumigraph rendering: the nodes' partial images (RGBA8, alpha =
// the node's share of the lumigraph weight, shareOfAlpha) normalised per pixel and blended:
//   rgb = sum_n share_n rgb_n / sum_n share_n,  alpha = 255 where any share > 0, else 0,
// then the silhouette feathered by a pixel (featherSilhouette: premultiplied). With one image that
// holds every camera (the single-process renderer) this is finishSingleProcessView of that image,
// so both paths give the same picture to rounding. It touches only the pixels the nodes drew (the
// actor covers a fraction of the view) and their neighbours: images are added straight from their
// wire encoding, and each row remembers the span it was drawn in, so that neither reset() nor
// finish() walks the empty rest. A tight CPU loop: at 640x480 it costs less than
// uploading the images to a GPU would (see docs/lumigraph.md).
class PartialImageBlender {
 public:
  // Starts a frame of width x height pixels. With the size unchanged, it keeps its buffers and
  // clears only the pixels the last frame drew.
  void reset(int width, int height);
  // One node's partial image, width*height*4 bytes; another size is ignored (returns false).
  bool add(std::span<const uint8_t> rgba);
  // The same in the alpha-runs encoding (core/imaging/partial_image_codec.h), without decoding
  // it; false, and nothing added, when `encoded` is not a valid encoding of width*height pixels.
  bool addAlphaRuns(std::span<const uint8_t> encoded);
  // The blended image, width*height*4 bytes; `rgba` is resized when its size differs.
  void finish(std::vector<uint8_t>& rgba) const;
  int width() const { return width_; }
  int height() const { return height_; }
  int added() const { return added_; }

 private:
  // Adds `count` pixels from pixel index `first` on (within one image, across rows if so).
  void accumulate(size_t first, const uint8_t* rgba, size_t count);

  int width_ = 0, height_ = 0, added_ = 0;
  std::vector<float> sums_;  // per pixel: sum of share * R, G, B, and sum of share
  // Per row, the columns [begin, end) that hold every pixel added since reset (begin >= end:
  // none).
  std::vector<int> row_begin_, row_end_;
};

}  // namespace lumistage
