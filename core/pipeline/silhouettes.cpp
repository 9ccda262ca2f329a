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

}  // namespace lumistage
