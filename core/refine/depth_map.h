#pragma once

#include <Eigen/Core>
#include <span>
#include <vector>

#include "core/geometry/camera.h"

namespace lumistage {

// A low-resolution depth map of a mesh seen by a camera, by a CPU z-buffer: the refinement's
// visibility test (the paper's "render the mesh from this camera and extract a low resolution
// depthmap"). A cell is `step` x `step` camera pixels; the depth is along the optical axis (what
// Camera::project returns). Reuse one object per camera: render() allocates only when the size
// grows.
class DepthMap {
 public:
  // Rasterises the triangles at the cells' centres (lens distortion applied at the vertices,
  // straight edges between them: fine at this resolution). Triangles with a vertex behind the
  // camera are left out, and so are back faces: the mesh is closed and wound counter-clockwise
  // seen from outside (as every mesh here), so the nearest surface is always a front face.
  // Triangles with a vertex index outside `positions` are left out.
  void render(const Camera& camera, const Eigen::Matrix3Xf& positions,
              std::span<const Eigen::Vector3i> triangles, int step);

  int width() const { return width_; }
  int height() const { return height_; }
  int step() const { return step_; }
  // The depth at a camera pixel's cell; +infinity where no triangle covers it or off the map.
  float depthAt(float pixel_x, float pixel_y) const {
    const int i = static_cast<int>((pixel_x + 0.5f) / float(step_));
    const int j = static_cast<int>((pixel_y + 0.5f) / float(step_));
    if (pixel_x < -0.5f || pixel_y < -0.5f || i >= width_ || j >= height_) return kFar;
    return depth_[size_t(j) * width_ + i];
  }
  // Whether a point at `depth` on that pixel is not hidden: no further than `tolerance_m` behind
  // the map.
  bool visible(float pixel_x, float pixel_y, float depth, float tolerance_m) const {
    return depth <= depthAt(pixel_x, pixel_y) + tolerance_m;
  }
  const std::vector<float>& depths() const { return depth_; }
  // What the last render() projected: every vertex's pixel and its depth along the optical axis.
  const Eigen::Matrix2Xf& vertexPixels() const { return pixels_; }
  const Eigen::VectorXf& vertexDepths() const { return depths_; }

  static constexpr float kFar = 1e30f;

 private:
  int width_ = 0, height_ = 0, step_ = 1;
  std::vector<float> depth_;
  Eigen::Matrix2Xf pixels_;
  Eigen::VectorXf depths_;
};

}  // namespace lumistage
