#include "core/refine/depth_map.h"

#include <algorithm>
#include <cmath>

namespace lumistage {

void DepthMap::render(const Camera& camera, const Eigen::Matrix3Xf& positions,
                      std::span<const Eigen::Vector3i> triangles, int step) {
  step_ = std::max(step, 1);
  width_ = (camera.width() + step_ - 1) / step_;
  height_ = (camera.height() + step_ - 1) / step_;
  depth_.assign(size_t(width_) * height_, kFar);
  camera.project(positions, pixels_, depths_);
  // Cell (i, j) covers camera pixels [i·step - 0.5, (i+1)·step - 0.5): its centre is at cell
  // coordinate i when u = (x + 0.5) / step - 0.5.
  const float inv = 1.0f / float(step_);
  for (const Eigen::Vector3i& t : triangles) {
    // Image rows go down: a front face (counter-clockwise from outside) turns clockwise, a
    // negative area below. The nearest surface of a closed mesh is always a front face, so back
    // faces are skipped; a front face's second and third corners swap to make its area positive.
    const int a = t[0], b = t[2], c = t[1];
    if (t.minCoeff() < 0 || t.maxCoeff() >= depths_.size()) continue;  // not of this mesh
    const float z0 = depths_[a], z1 = depths_[b], z2 = depths_[c];
    if (z0 <= 0 || z1 <= 0 || z2 <= 0) continue;
    const float x0 = (pixels_(0, a) + 0.5f) * inv - 0.5f, y0 = (pixels_(1, a) + 0.5f) * inv - 0.5f;
    const float x1 = (pixels_(0, b) + 0.5f) * inv - 0.5f, y1 = (pixels_(1, b) + 0.5f) * inv - 0.5f;
    const float x2 = (pixels_(0, c) + 0.5f) * inv - 0.5f, y2 = (pixels_(1, c) + 0.5f) * inv - 0.5f;
    const float area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
    if (area < 1e-12f) continue;
    const int i0 = std::max(0, static_cast<int>(std::ceil(std::min({x0, x1, x2}))));
    const int i1 = std::min(width_ - 1, static_cast<int>(std::floor(std::max({x0, x1, x2}))));
    const int j0 = std::max(0, static_cast<int>(std::ceil(std::min({y0, y1, y2}))));
    const int j1 = std::min(height_ - 1, static_cast<int>(std::floor(std::max({y0, y1, y2}))));
    if (i0 > i1 || j0 > j1) continue;
    // Edge functions, linear in the cell (i, j): e0 = area·w0, e1 = area·w1, e2 = area·w2, the
    // barycentric weights of the cell centre; the depth is linear too.
    const float a0 = y1 - y2, b0 = x2 - x1, c0 = x1 * y2 - x2 * y1;
    const float a1 = y2 - y0, b1 = x0 - x2, c1 = x2 * y0 - x0 * y2;
    const float ia = 1.0f / area;
    const float dz_di = (a0 * (z0 - z2) + a1 * (z1 - z2)) * ia;
    for (int j = j0; j <= j1; ++j) {
      float e0 = a0 * float(i0) + b0 * float(j) + c0;
      float e1 = a1 * float(i0) + b1 * float(j) + c1;
      float z = z2 + (e0 * (z0 - z2) + e1 * (z1 - z2)) * ia;
      float* row = &depth_[size_t(j) * width_];
      for (int i = i0; i <= i1; ++i, e0 += a0, e1 += a1, z += dz_di) {
        if (e0 < 0 || e1 < 0 || area - e0 - e1 < 0) continue;
        if (z < row[i]) row[i] = z;
      }
    }
  }
}

}  // namespace lumistage
