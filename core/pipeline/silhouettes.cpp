#include "core/pipeline/silhouettes.h"

#include <algorithm>

namespace lumistage {

void computeSilhouette(const GreenScreenKeyer& key, const ImageView& image, int camera, int step,
                       LowResSilhouette& out) {
  out.camera = camera;
  out.step = step;
  out.width = image.width / step;
  out.height = image.height / step;
  out.bits.assign((size_t(out.width) * out.height + 7) / 8, 0);
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      if (key.isForeground(image, x * step + step / 2, y * step + step / 2)) {
        const size_t i = size_t(y) * out.width + x;
        out.bits[i / 8] |= uint8_t(1u << (i % 8));
      }
    }
  }
}

void silhouetteMask(const LowResSilhouette& s, int grow_cells, std::vector<uint8_t>& out) {
  out.assign(size_t(s.width) * s.height, 0);
  for (int y = 0; y < s.height; ++y) {
    for (int x = 0; x < s.width; ++x) {
      if (!s.at(x, y)) continue;
      for (int v = std::max(0, y - grow_cells); v <= std::min(s.height - 1, y + grow_cells); ++v) {
        uint8_t* row = &out[size_t(v) * s.width];
        std::fill(row + std::max(0, x - grow_cells), row + std::min(s.width, x + grow_cells + 1),
                  uint8_t(255));
      }
    }
  }
}

}  // namespace lumistage
