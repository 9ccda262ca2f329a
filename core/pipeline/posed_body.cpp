#include "core/pipeline/posed_body.h"

namespace lumistage {

Pose poseFromMessage(const PoseData& data, int joint_count) {
  Pose pose = Pose::rest(joint_count);
  pose.root_translation_m = Eigen::Vector3d(data.root[0], data.root[1], data.root[2]);
  for (int j = 0; j < joint_count && 3 * j + 2 < static_cast<int>(data.angles.size()); ++j) {
    pose.angles_rad[j] =
        Eigen::Vector3d(data.angles[3 * j], data.angles[3 * j + 1], data.angles[3 * j + 2]);
  }
  return pose;
}

PoseData poseMessageFor(const Eigen::Vector3d& generic_root_m, const Skeleton& calibrated,
                        const Pose& tracked) {
  const Eigen::Vector3d actor_root = calibrated.restPositions()[0];
  const double scale = actor_root.z() / generic_root_m.z();
  const Eigen::Vector3d root = (actor_root + tracked.root_translation_m) / scale - generic_root_m;
  PoseData data;
  data.scale = float(scale);
  for (int k = 0; k < 3; ++k) data.root[k] = float(root[k]);
  data.angles.reserve(tracked.angles_rad.size() * 3);
  for (const Eigen::Vector3d& a : tracked.angles_rad)
    data.angles.insert(data.angles.end(), {float(a.x()), float(a.y()), float(a.z())});
  return data;
}

void posedBodyMesh(const SkinnedMesh& body, const PoseData& data,
                   std::vector<Eigen::Affine3f>& transforms, Eigen::Matrix3Xf& positions,
                   Eigen::Matrix3Xf& normals) {
  body.skeleton.skinningTransforms(poseFromMessage(data, body.skeleton.jointCount()), transforms);
  skinMesh(body, transforms, positions, normals);
  if (data.scale != 1.0f) positions *= data.scale;
}

}  // namespace lumistage
