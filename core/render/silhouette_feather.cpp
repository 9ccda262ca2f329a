#include "core/render/silhouette_feather.h"

#include <algorithm>
#include <cstddef>

#include "core/base/error.h"

namespace lumistage {

namespace {

// Alpha (of 255) of an empty pixel by its count of opaque 8-neighbours: the share of such pixels
// that the actor covered on the four reference clips (leave-one-camera-out, refined meshes, two
// frames each; docs/lumigraph.md). At most 254: a feathered pixel never counts as opaque.
constexpr uint8_t kFeatherAlpha[9] = {0, 4, 8, 20, 69, 115, 115, 153, 254};

}  // namespace

void featherSilhouette(std::span<uint8_t> rgba, int width, int height,
                       std::span<const int> row_begin, std::span<const int> row_end) {
  if (width <= 0 || height <= 0 || rgba.size() != size_t(width) * height * 4)
    throw Error("featherSilhouette: an RGBA8 image of " + std::to_string(width) + "x" +
                std::to_string(height) + " expected");
  const bool spans = !row_begin.empty();
  if (spans && (row_begin.size() != size_t(height) || row_end.size() != size_t(height)))
    throw Error("featherSilhouette: a span for each of the " + std::to_string(height) +
                " rows expected");
  const size_t stride = size_t(width) * 4;
  const auto opaque = [&](int x, int y) {
    return rgba[size_t(y) * stride + size_t(x) * 4 + 3] == 255;
  };
  for (int y = 0; y < height; ++y) {
    const int y0 = std::max(0, y - 1), y1 = std::min(height - 1, y + 1);
    int x0 = 0, x1 = width;
    if (spans) {
      x0 = width, x1 = 0;
      for (int r = y0; r <= y1; ++r)
        if (row_begin[r] < row_end[r])
          x0 = std::min(x0, row_begin[r]), x1 = std::max(x1, row_end[r]);
      if (x0 >= x1) continue;
      x0 = std::max(0, x0 - 1), x1 = std::min(width, x1 + 1);
    }
    for (int x = x0; x < x1; ++x) {
      uint8_t* p = rgba.data() + size_t(y) * stride + size_t(x) * 4;
      if (p[3] == 255) continue;
      int count = 0, sum[3] = {0, 0, 0};
      for (int r = y0; r <= y1; ++r)
        for (int c = std::max(0, x - 1); c <= std::min(width - 1, x + 1); ++c) {
          if (!opaque(c, r)) continue;
          const uint8_t* q = rgba.data() + size_t(r) * stride + size_t(c) * 4;
          sum[0] += q[0], sum[1] += q[1], sum[2] += q[2];
          ++count;
        }
      if (count == 0) continue;
      const int a = kFeatherAlpha[count];
      for (int k = 0; k < 3; ++k) p[k] = uint8_t((sum[k] * a + count * 255 / 2) / (count * 255));
      p[3] = uint8_t(a);
    }
  }
}

void finishSingleProcessView(std::span<uint8_t> rgba, int width, int height) {
  for (size_t i = 3; i < rgba.size(); i += 4)
    if (rgba[i]) rgba[i] = 255;
  featherSilhouette(rgba, width, height);
}

}  // namespace lumistage
