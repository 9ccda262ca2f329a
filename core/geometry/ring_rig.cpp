#include "core/geometry/ring_rig.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace lumistage {

Eigen::Matrix3d aimedRotation(const Eigen::Vector3d& centre, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - centre).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d R;
  R.row(0) = x.transpose();
  R.row(1) = y.transpose();
  R.row(2) = z.transpose();
  return R;
}

Rig makeRingRig(const RingRigSpec& spec) {
  if (spec.cameras <= 0 || spec.heights_m.empty() || !(spec.radius_m > 0) ||
      !(spec.vertical_fov_deg > 0 && spec.vertical_fov_deg < 170)) {
    throw std::invalid_argument(
        "ring rig: expected a positive camera count and radius, at least one height and a "
        "vertical field of view in (0, 170) degrees");
  }
  const double f =
      0.5 * spec.height / std::tan(0.5 * spec.vertical_fov_deg * std::numbers::pi / 180);
  const Intrinsics intrinsics{f, f, 0.5 * (spec.width - 1), 0.5 * (spec.height - 1), 0.0};
  std::vector<Camera> cameras;
  for (int i = 0; i < spec.cameras; ++i) {
    const double angle = 2 * std::numbers::pi * i / spec.cameras;
    const Eigen::Vector3d centre(spec.radius_m * std::cos(angle), spec.radius_m * std::sin(angle),
                                 spec.heights_m[i % spec.heights_m.size()]);
    const Eigen::Matrix3d R = aimedRotation(centre, spec.target_m);
    cameras.emplace_back(fmt::format("cam{:02}", i + 1), spec.width, spec.height, intrinsics,
                         spec.distortion, R, -R * centre);
  }
  return Rig(std::move(cameras), dealCamerasToNodes(spec.cameras, spec.cameras_per_node));
}

}  // namespace lumistage
