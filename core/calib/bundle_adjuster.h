#pragma once

#include <Eigen/Core>
#include <vector>

namespace lumistage {

// A camera as the bundle adjustment sees it: square pixels, no skew, radial distortion k1 k2
// (OpenCV's model with p1 = p2 = k3 = 0), pose as an angle-axis rotation and a translation
// (x_cam = R·X + t).
struct BundleCamera {
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();  // angle-axis, radians
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  double focal_px = 1000, cx = 0, cy = 0, k1 = 0, k2 = 0;
};

struct BundleObservation {
  int camera = 0;
  int point = 0;
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
};

struct BundleOptions {
  bool refine_intrinsics = true;       // focal length and principal point
  bool refine_distortion = true;       // k1, k2 (needs refine_intrinsics)
  bool refine_principal_point = true;  // (needs refine_intrinsics)
  // > 0: Huber loss of this scale (pixels), so that outliers pull less; 0: plain least squares.
  double huber_px = 0;
  int max_iterations = 100;
  // The gauge: this camera's pose is held fixed, and scale_camera's distance from it too (its
  // translation moves on a sphere), leaving no free similarity.
  int fixed_camera = 0;
  int scale_camera = 1;
};

struct BundleResult {
  double initial_rms_px = 0;
  double final_rms_px = 0;
  int iterations = 0;
  bool converged = false;
};

// Minimises the reprojection error over cameras and points (Ceres, Levenberg-Marquardt, Schur
// complement on the points).
BundleResult adjustBundle(std::vector<BundleCamera>& cameras, std::vector<Eigen::Vector3d>& points,
                          const std::vector<BundleObservation>& observations,
                          const BundleOptions& options);

// The pixel of a point seen by a bundle camera; empty behind it.
bool projectBundle(const BundleCamera& camera, const Eigen::Vector3d& point,
                   Eigen::Vector2d& pixel);

}  // namespace lumistage
