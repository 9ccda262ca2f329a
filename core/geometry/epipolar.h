#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/geometry/camera.h"

namespace lumistage {

// The fundamental matrix F from camera a's ideal (undistorted) pixels to camera b's:
// x_b^T F x_a = 0 for the images of one world point (homogeneous pixels, distortion left out).
Eigen::Matrix3d fundamentalMatrix(const Camera& a, const Camera& b);

// Camera b's image of the ray through camera a's (distorted) `pixel`, from `near_m` to `far_m`
// along it: the epipolar line, bent by b's lens. The ray is subdivided until neighbouring points
// are at most `max_step_px` apart; only points in front of b and within its image widened by a
// quarter on each side (where its lens model holds) are kept, in order along the ray. Empty when
// the pixel cannot be undistorted or the ray misses that part of b's view.
std::vector<Eigen::Vector2d> epipolarCurve(const Camera& a, const Eigen::Vector2d& pixel,
                                           const Camera& b, double near_m = 0.2,
                                           double far_m = 30.0, double max_step_px = 2.0);

// Distance in pixels from `point` to a polyline (infinity for an empty one).
double distanceToPolyline(const std::vector<Eigen::Vector2d>& polyline,
                          const Eigen::Vector2d& point);

}  // namespace lumistage
