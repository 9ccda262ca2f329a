#include "core/pipeline/silhouettes.h"

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
      if (keyCell(key, image, x, y, step)) {
        const size_t i = size_t(y) * out.width + x;
        out.bits[i / 8] |= uint8_t(1u << (i % 8));
      }
    }
  }
}

void silhouetteMask(const LowResSilhouette& s, std::vector<uint8_t>& out) {
  const size_t cells = size_t(s.width) * s.height;
  out.resize(cells);
  for (size_t i = 0; i < cells; ++i) out[i] = uint8_t(0u - ((s.bits[i >> 3] >> (i & 7)) & 1u));
}

}  // namespace lumistage
