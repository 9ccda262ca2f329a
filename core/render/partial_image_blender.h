#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace lumistage {

// The studio's side of distributed lumigraph rendering: the nodes' partial images (RGBA8, alpha =
// the node's share of the lumigraph weight, LumigraphRenderer) normalised per pixel and blended:
//   rgb = sum_n alpha_n rgb_n / sum_n alpha_n,  alpha = 255 where sum_n alpha_n > 0, else 0.
// With one image that holds every camera (the single-process renderer) this is that image with
// its alpha made opaque, so both paths give the same picture to rounding. A tight CPU loop: at
// 640x480 it costs less than uploading the images to a GPU would (see docs/lumigraph.md).
class PartialImageBlender {
 public:
  // Starts a frame of width x height pixels (keeps the buffers when the size is unchanged).
  void reset(int width, int height);
  // One node's partial image, width*height*4 bytes; another size is ignored (returns false).
  bool add(std::span<const uint8_t> rgba);
  // The blended image, width*height*4 bytes; `rgba` is resized when its size differs.
  void finish(std::vector<uint8_t>& rgba) const;
  int width() const { return width_; }
  int height() const { return height_; }
  int added() const { return added_; }

 private:
  int width_ = 0, height_ = 0, added_ = 0;
  std::vector<uint32_t> sums_;  // per pixel: sum of alpha * R, G, B, and sum of alpha
};

}  // namespace lumistage
