#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/geometry/rig.h"

namespace lumistage {

// x' = scale · R · x + t: the gauge of a self-calibration (its frame and scale are arbitrary)
// moved to the world's.
struct Similarity {
  double scale = 1;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  Eigen::Vector3d apply(const Eigen::Vector3d& x) const { return scale * R * x + t; }
  // The same cameras seen from the new frame (intrinsics unchanged).
  Camera apply(const Camera& camera) const;
  Rig apply(const Rig& rig) const;
};

// Whether points lie (nearly) on a line: the spread across their main direction is below
// `ratio` of the spread along it (singular values of the centred points). A rotation about that
// line is then left to noise.
bool nearlyOnALine(const std::vector<Eigen::Vector3d>& points, double ratio = 0.01);

// Least-squares similarity (Umeyama 1991) taking `from` onto `to` (same length, >= 3 points not
// all on a line: throws Error otherwise); with_scale = false gives a rigid motion.
Similarity alignPoints(const std::vector<Eigen::Vector3d>& from,
                       const std::vector<Eigen::Vector3d>& to, bool with_scale = true);

// How far an estimated rig is from the truth once the gauge is fixed by aligning the estimated
// camera centres to the true ones (similarity); rotations are compared after the same alignment.
struct CameraError {
  std::string name;
  double centre_m = 0;
  double rotation_deg = 0;
  double focal_rel = 0;  // |f_est - f_true| / f_true
  // The intrinsics (focal length, principal point and lens together) compared where it matters:
  // the largest distance between where the two cameras put the same ray in the camera frame,
  // over a grid on the image (its outer 5% left out).
  double intrinsics_px = 0;
};
struct RigComparison {
  std::vector<CameraError> cameras;
  double max_centre_m = 0, rms_centre_m = 0, max_rotation_deg = 0, max_focal_rel = 0;
  double max_intrinsics_px = 0;
  Similarity alignment;
};
// Cameras are matched by name; throws Error naming a camera missing from either rig.
RigComparison compareRigs(const Rig& estimate, const Rig& truth, bool align = true);

double rotationAngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b);
// CameraError::intrinsics_px of two cameras of the same image size; or the same over given pixels
// of the truth's image (e.g. where the calibration had samples: a lens model is only known there).
double intrinsicsDifferencePx(const Camera& estimate, const Camera& truth);
double intrinsicsDifferencePx(const Camera& estimate, const Camera& truth,
                              const std::vector<Eigen::Vector2d>& pixels);

}  // namespace lumistage
