#include "core/render/partial_image_blender.h"

#include <algorithm>

namespace lumistage {

void PartialImageBlender::reset(int width, int height) {
  width_ = width;
  height_ = height;
  added_ = 0;
  sums_.assign(size_t(width) * height * 4, 0);
}

bool PartialImageBlender::add(std::span<const uint8_t> rgba) {
  const size_t pixels = size_t(width_) * height_;
  if (rgba.size() != pixels * 4) return false;
  uint32_t* s = sums_.data();
  const uint8_t* p = rgba.data();
  for (size_t i = 0; i < pixels; ++i, s += 4, p += 4) {
    const uint32_t a = p[3];
    if (a == 0) continue;
    s[0] += a * p[0];
    s[1] += a * p[1];
    s[2] += a * p[2];
    s[3] += a;
  }
  ++added_;
  return true;
}

void PartialImageBlender::finish(std::vector<uint8_t>& rgba) const {
  const size_t pixels = size_t(width_) * height_;
  if (rgba.size() != pixels * 4) rgba.resize(pixels * 4);
  const uint32_t* s = sums_.data();
  uint8_t* out = rgba.data();
  for (size_t i = 0; i < pixels; ++i, s += 4, out += 4) {
    const uint32_t a = s[3];
    if (a == 0) {
      out[0] = out[1] = out[2] = out[3] = 0;
      continue;
    }
    for (int k = 0; k < 3; ++k) out[k] = static_cast<uint8_t>((s[k] + a / 2) / a);
    out[3] = 255;
  }
}

}  // namespace lumistage
