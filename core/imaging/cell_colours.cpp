#include "core/imaging/cell_colours.h"

#include <algorithm>
#include <bit>

#include "core/imaging/keyer.h"

namespace lumistage {

namespace {

// Calls f(cx, cy) for every set cell of `s`, in its bits' order.
template <typename F>
void forEachSetCell(const LowResSilhouette& s, F&& f) {
  const size_t cells = size_t(s.width) * s.height;
  for (size_t byte = 0; byte < s.bits.size(); ++byte) {
    unsigned bits = s.bits[byte];
    while (bits != 0) {
      const size_t i = byte * 8 + size_t(std::countr_zero(bits));
      bits &= bits - 1;
      if (i >= cells) return;
      f(int(i % size_t(s.width)), int(i / size_t(s.width)));
    }
  }
}

}  // namespace

size_t countActorCells(const uint8_t* bits, size_t bytes, size_t cells) {
  size_t set = 0;
  for (size_t k = 0; k < bytes && k * 8 < cells; ++k) {
    unsigned byte = bits[k];
    if (k * 8 + 8 > cells) byte &= (1u << (cells - k * 8)) - 1;
    set += size_t(std::popcount(byte));
  }
  return set;
}

void sampleSilhouetteColours(const ImageView& image, const LowResSilhouette& silhouette,
                             std::vector<uint8_t>& out) {
  out.clear();
  const int step = silhouette.step;
  // A Bayer image's colour comes a 2x2 cell at a time: one read per Bayer cell of the step.
  const bool bayer = image.format != PixelFormat::kRgb8 && image.format != PixelFormat::kMono8;
  const int stride = bayer ? 2 : 1;
  forEachSetCell(silhouette, [&](int cx, int cy) {
    int r = 0, g = 0, b = 0, n = 0;
    const int x0 = cx * step, y0 = cy * step;
    const int x1 = std::min(x0 + step, image.width), y1 = std::min(y0 + step, image.height);
    for (int y = y0; y < y1; y += stride) {
      for (int x = x0; x < x1; x += stride) {
        const Rgb c = colourAt(image, x, y);
        r += c.r, g += c.g, b += c.b;
        ++n;
      }
    }
    n = std::max(n, 1);
    out.push_back(uint8_t((r + n / 2) / n));
    out.push_back(uint8_t((g + n / 2) / n));
    out.push_back(uint8_t((b + n / 2) / n));
  });
}

bool expandSilhouetteColours(const LowResSilhouette& silhouette, const uint8_t* packed,
                             size_t count, CellColours& out) {
  out.camera = silhouette.camera;
  out.step = silhouette.step;
  out.width = silhouette.width;
  out.height = silhouette.height;
  out.rgb.clear();
  const size_t set = countActorCells(silhouette.bits.data(), silhouette.bits.size(),
                                     size_t(silhouette.width) * silhouette.height);
  if (count != 3 * set) return false;
  out.rgb.assign(size_t(out.width) * out.height * 3, 0);
  size_t k = 0;
  forEachSetCell(silhouette, [&](int cx, int cy) {
    uint8_t* q = out.rgb.data() + 3 * (size_t(cy) * out.width + cx);
    std::copy(packed + k, packed + k + 3, q);
    k += 3;
  });
  return true;
}

void sampleCellColours(const ImageView& image, const LowResSilhouette& silhouette,
                       CellColours& out) {
  std::vector<uint8_t> packed;
  sampleSilhouetteColours(image, silhouette, packed);
  expandSilhouetteColours(silhouette, packed.data(), packed.size(), out);
}

}  // namespace lumistage
