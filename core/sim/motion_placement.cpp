#include "core/sim/motion_placement.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <numbers>

#include "core/base/error.h"
#include "core/geometry/rotation.h"

namespace lumistage {

void placeMotion(MotionClip& clip, const Skeleton& skeleton, const MotionPlacement& placement,
                 int frame_count, double fps) {
  if (placement.start_s > clip.durationSeconds())
    throw Error(fmt::format("motion '{}': starts at {:.2f} s, past its end ({:.2f} s)", clip.name,
                            placement.start_s, clip.durationSeconds()));
  const Eigen::Vector3d rest_root = skeleton.joint(0).offset_m;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  if (placement.centre) {
    for (int f = 0; f < frame_count; ++f)
      centre += (rest_root + clip.sample(placement.start_s + f / fps).root_translation_m).head<2>();
    centre /= std::max(1, frame_count);
  }
  const Eigen::AngleAxisd turn(placement.heading_deg * std::numbers::pi / 180,
                               Eigen::Vector3d::UnitZ());
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  shift.head<2>() = placement.offset_m;
  for (Pose& pose : clip.frames) {
    Eigen::Vector3d root = rest_root + pose.root_translation_m;
    root.head<2>() -= centre;
    pose.root_translation_m = turn * root + shift - rest_root;
    if (pose.angles_rad.empty()) continue;
    pose.angles_rad[0] =
        rotationVectorOf(turn.toRotationMatrix() * rotationFromVector(pose.angles_rad[0]));
  }
}

}  // namespace lumistage
