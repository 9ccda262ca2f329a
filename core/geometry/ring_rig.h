#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/geometry/rig.h"

namespace lumistage {

// A ring of cameras around the stage, all aimed at a point above its centre, heights alternating
// through `heights_m` (e.g. high, low). The reference rig is the default: 12 cameras at 1024x768,
// 3 a node, 3.6 m from the centre of a 3x3 m stage, alternately 2.3 m and 0.9 m high, each
// seeing a 2 m tall actor anywhere on the stage.
struct RingRigSpec {
  int cameras = 12;
  int cameras_per_node = 3;
  int width = 1024;
  int height = 768;
  double radius_m = 3.6;
  std::vector<double> heights_m = {2.3, 0.9};
  Eigen::Vector3d target_m = {0.0, 0.0, 1.0};
  double vertical_fov_deg = 52.0;
  Distortion distortion = {-0.06, 0.015, 0.0, 0.0, 0.0};  // mild barrel, as wide lenses have
};

Rig makeRingRig(const RingRigSpec& spec);

// The world-to-camera rotation of a camera at `centre` aimed at `target`, its horizon level: the
// camera's z toward the target, x horizontal, y down.
Eigen::Matrix3d aimedRotation(const Eigen::Vector3d& centre, const Eigen::Vector3d& target);

}  // namespace lumistage
