#pragma once

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/calib/calibration_report.h"
#include "core/calib/wand_session.h"
#include "core/geometry/rig.h"

namespace lumistage {

struct WandCalibrationOptions {
  // Where the solve starts from: the intrinsics (and node assignment) of this rig's cameras of
  // the same names — e.g. the lens makers' focal lengths or an older calibration; poses are not
  // used. Without it: focal length from nominal_hfov_deg, principal point at the image centre,
  // no distortion.
  std::optional<Rig> initial_rig;
  double nominal_hfov_deg = 60;
  int cameras_per_node = 3;        // node assignment without an initial rig
  double ransac_threshold_px = 4;  // for the two-view and camera-resection RANSAC
  // Observations whose error after the robust bundle adjustment exceeds
  // max(min_outlier_threshold_px, 4 sigma) are rejected (sigma: the noise, estimated robustly).
  double min_outlier_threshold_px = 1.0;
  int min_points_per_camera = 20;
  int min_samples = 30;  // samples seen by two or more cameras
  bool refine_distortion = true;
  // The principal point is weakly determined by a wand session (with a ring of cameras it trades
  // off against the cameras' rotations: 1 px is 0.07 degree at f = 800 px): freed where it sits
  // where it starts (the image centre, or an initial rig's), it costs accuracy (the reference
  // ring, 1000 samples: centres 4.1 -> 8.8 mm); held where the lenses' sit off centre, it costs
  // more (up to 14 px off: 28 mm and 1.1 degrees, 13 mm and 0.2 freed). kAuto lets the data
  // decide: the solve with it held, then freed from there on the same observations, and freed
  // is kept when that lowers the reprojection RMS by kPrincipalPointGain or more (noise alone
  // buys about a thousandth with 12 cameras' two more unknowns each). The report says which.
  enum class PrincipalPoint { kAuto, kFixed, kRefined };
  PrincipalPoint principal_point = PrincipalPoint::kAuto;
  static constexpr double kPrincipalPointGain = 0.03;
  double wand_length_m = 0;  // > 0: the session's wand pairs give the scale
  // (stage, done, total) while solving: stages "init", "resection", "bundle".
  std::function<void(const std::string&, int, int)> progress;
};

struct WandCalibrationResult {
  Rig rig;
  std::vector<Eigen::Vector3d> points_m;     // per sample, in the rig's frame
  std::vector<uint8_t> point_valid;          // whether the sample was reconstructed
  std::vector<std::vector<uint8_t>> inlier;  // [sample][camera]
  int outliers_rejected = 0;
  CalibrationReport report;
};

// Self-calibration of a rig from a wand session (in the spirit of Svoboda et al. 2005; the
// method is described in docs/calibration.md): a robust two-view start (essential matrix,
// RANSAC) on the pair of cameras sharing most samples, cameras added one by one by RANSAC
// resection, outliers rejected, and a bundle adjustment (Ceres) of poses, focal lengths,
// principal points, k1, k2 and points. Then the gauge: wand length for the scale, floor marks
// for the floor and heading. Throws Error naming the camera for a session that cannot be solved
// (a camera that saw nothing or too little, a camera that shares too few samples).
WandCalibrationResult calibrateWand(const WandSession& session,
                                    const WandCalibrationOptions& options);

}  // namespace lumistage
