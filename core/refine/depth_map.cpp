#include "core/refine/depth_map.h"

#include <algorithm>
#include <cmath>

namespace lumistage {

void DepthMap::render(const Camera& camera, const Eigen::Matrix3Xf& positions,
                      const std::vector<Eigen::Vector3i>& triangles, int step) {
  step_ = std::max(step, 1);
  width_ = (camera.width() + step_ - 1) / step_;
  height_ = (camera.height() + step_ - 1) / step_;
  depth_.assign(size_t(width_) * height_, kFar);
  camera.project(positions, pixels_, depths_);
  // Cell (i, j) covers camera pixels [i·step - 0.5, (i+1)·step - 0.5): its centre is at cell
  // coordinate i when u = (x + 0.5) / step - 0.5.
  const float inv = 1.0f / float(step_);
  for (const Eigen::Vector3i& t : triangles) {
    const float z0 = depths_[t[0]], z1 = depths_[t[1]], z2 = depths_[t[2]];
    if (z0 <= 0 || z1 <= 0 || z2 <= 0) continue;
    const float x0 = (pixels_(0, t[0]) + 0.5f) * inv - 0.5f,
                y0 = (pixels_(1, t[0]) + 0.5f) * inv - 0.5f;
    const float x1 = (pixels_(0, t[1]) + 0.5f) * inv - 0.5f,
                y1 = (pixels_(1, t[1]) + 0.5f) * inv - 0.5f;
    const float x2 = (pixels_(0, t[2]) + 0.5f) * inv - 0.5f,
                y2 = (pixels_(1, t[2]) + 0.5f) * inv - 0.5f;
    const float area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
    if (std::abs(area) < 1e-12f) continue;
    const int i0 = std::max(0, static_cast<int>(std::ceil(std::min({x0, x1, x2}))));
    const int i1 = std::min(width_ - 1, static_cast<int>(std::floor(std::max({x0, x1, x2}))));
    const int j0 = std::max(0, static_cast<int>(std::ceil(std::min({y0, y1, y2}))));
    const int j1 = std::min(height_ - 1, static_cast<int>(std::floor(std::max({y0, y1, y2}))));
    const float ia = 1.0f / area;
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        // Barycentric weights of the cell centre (either winding: both faces are drawn).
        const float w0 =
            ((x1 - float(i)) * (y2 - float(j)) - (x2 - float(i)) * (y1 - float(j))) * ia;
        const float w1 =
            ((x2 - float(i)) * (y0 - float(j)) - (x0 - float(i)) * (y2 - float(j))) * ia;
        const float w2 = 1.0f - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const float z = w0 * z0 + w1 * z1 + w2 * z2;
        float& d = depth_[size_t(j) * width_ + i];
        if (z < d) d = z;
      }
    }
  }
}

}  // namespace lumistage
