#include "core/tracking/tracked_mesh.h"

#include <vector>

namespace lumistage {

void poseTrackedMesh(const SkinnedMesh& generic, const Skeleton& calibrated, const Pose& tracked,
                     Eigen::Matrix3Xf& positions, Eigen::Matrix3Xf& normals) {
  const Eigen::Vector3d generic_root = generic.skeleton.restPositions()[0];
  const Eigen::Vector3d actor_root = calibrated.restPositions()[0];
  const double scale = actor_root.z() / generic_root.z();
  // Posed at 1/scale of the world, then scaled up about the origin (the floor's centre): the
  // pelvis lands at actor_root + translation.
  Pose pose = tracked;
  pose.root_translation_m = (actor_root + tracked.root_translation_m) / scale - generic_root;
  thread_local std::vector<Eigen::Affine3f> transforms;
  generic.skeleton.skinningTransforms(pose, transforms);
  skinMesh(generic, transforms, positions, normals);
  positions *= float(scale);
}

}  // namespace lumistage
