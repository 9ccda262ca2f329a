#include "core/pipeline/silhouettes.h"

#include <algorithm>

namespace lumistage {

void computeSilhouette(const GreenScreenKeyer& key, const ImageView& image, int camera, int step,
                       LowResSilhouette& out) {
  out.camera = camera;
  out.step = step;
  out.width = image.width / step;
  out.height = image.height / step;
  const int row_bytes = out.bytesPerRow();
  out.bits.assign(size_t(row_bytes) * out.height, 0);
  for (int y = 0; y < out.height; ++y) {
    uint8_t* row = out.bits.data() + size_t(y) * row_bytes;
    for (int x = 0; x < out.width; ++x) {
      if (key.isForeground(image, x * step + step / 2, y * step + step / 2))
        row[x / 8] |= uint8_t(1u << (x % 8));
    }
  }
}

}  // namespace lumistage
