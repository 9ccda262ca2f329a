#include "core/tracking/mesh_silhouette.h"

#include <algorithm>
#include <cmath>

namespace lumistage {

void rasterizeSilhouette(const Eigen::Matrix3Xf& positions,
                         const std::vector<Eigen::Vector3i>& triangles, const Camera& camera,
                         int camera_index, int step, LowResSilhouette& out) {
  out.camera = camera_index;
  out.step = step;
  out.width = camera.width() / step;
  out.height = camera.height() / step;
  out.bits.assign((size_t(out.width) * out.height + 7) / 8, 0);
  Eigen::Matrix2Xf pixels;
  Eigen::VectorXf depths;
  camera.project(positions, pixels, depths);
  // Cell (x, y) samples pixel (x * step + step / 2, y * step + step / 2): in cell units the
  // sample sits at integer coordinates after this shift.
  const float half = float(step / 2), inv = 1.0f / float(step);
  for (const Eigen::Vector3i& t : triangles) {
    if (depths(t[0]) <= 0 || depths(t[1]) <= 0 || depths(t[2]) <= 0) continue;
    Eigen::Vector2f p[3];
    for (int k = 0; k < 3; ++k) p[k] = (pixels.col(t[k]).array() - half) * inv;
    const float min_x = std::min({p[0].x(), p[1].x(), p[2].x()}),
                max_x = std::max({p[0].x(), p[1].x(), p[2].x()}),
                min_y = std::min({p[0].y(), p[1].y(), p[2].y()}),
                max_y = std::max({p[0].y(), p[1].y(), p[2].y()});
    const int x0 = std::max(0, int(std::ceil(min_x))), x1 = std::min(out.width - 1, int(max_x)),
              y0 = std::max(0, int(std::ceil(min_y))), y1 = std::min(out.height - 1, int(max_y));
    if (x0 > x1 || y0 > y1) continue;
    const float area =
        (p[1] - p[0]).x() * (p[2] - p[0]).y() - (p[1] - p[0]).y() * (p[2] - p[0]).x();
    if (area == 0) continue;
    const float s = area > 0 ? 1.0f : -1.0f;
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const Eigen::Vector2f q{float(x), float(y)};
        bool inside = true;
        for (int k = 0; k < 3 && inside; ++k) {
          const Eigen::Vector2f a = p[k], b = p[(k + 1) % 3];
          const float e = (b - a).x() * (q - a).y() - (b - a).y() * (q - a).x();
          inside = s * e >= 0;
        }
        if (inside) out.set(x, y);
      }
    }
  }
}

}  // namespace lumistage
