#include "core/net/posed_body.h"

#include "core/body/joint_pose_fit.h"

namespace lumistage {

Pose poseFromMessage(const PoseData& data, int joint_count) {
  Pose pose;
  poseFromMessage(data, joint_count, pose);
  return pose;
}

void poseFromMessage(const PoseData& data, int joint_count, Pose& pose) {
  pose.angles_rad.assign(joint_count, Eigen::Vector3d::Zero());
  pose.root_translation_m = Eigen::Vector3d(data.root[0], data.root[1], data.root[2]);
  for (int j = 0; j < joint_count && 3 * j + 2 < static_cast<int>(data.angles.size()); ++j) {
    pose.angles_rad[j] =
        Eigen::Vector3d(data.angles[3 * j], data.angles[3 * j + 1], data.angles[3 * j + 2]);
  }
}

PoseData poseMessageFor(const Skeleton& generic, const Skeleton& calibrated, const Pose& tracked,
                        const std::vector<Eigen::Vector3d>& joints) {
  // The uniform scale that brings the generic rest skeleton nearest the calibrated one (both stand
  // on the floor at the origin).
  const std::vector<Eigen::Vector3d>& g = generic.restPositions();
  const std::vector<Eigen::Vector3d>& c = calibrated.restPositions();
  double gc = 0, gg = 0;
  for (size_t j = 0; j < g.size() && j < c.size(); ++j)
    gc += g[j].dot(c[j]), gg += g[j].squaredNorm();
  JointPoseFit fit;
  fit.scale = gg > 0 ? gc / gg : 1.0;
  fit.pose = tracked;
  fit.pose.root_translation_m = (c[0] + tracked.root_translation_m) / fit.scale - g[0];
  JointPoseFitOptions options;
  options.fit_scale = false;
  // The tracker's capsules are round: it cannot see a twist about a bone, and its angles carry
  // whatever twist the fit drifted to. Drawn toward the rest pose's, leave-one-camera-out rose on
  // the arm wave (23.57 -> 23.70 dB matte); toward the tracked angles it fell below the old
  // scaling.
  options.prior_at_rest = true;
  options.max_iterations = 8;  // from the tracked angles: 1.2 ms
  fit = fitPoseToJoints(generic, joints, fit, options);
  PoseData data;
  data.scale = float(fit.scale);
  for (int k = 0; k < 3; ++k) data.root[k] = float(fit.pose.root_translation_m[k]);
  data.angles.reserve(fit.pose.angles_rad.size() * 3);
  for (const Eigen::Vector3d& a : fit.pose.angles_rad)
    data.angles.insert(data.angles.end(), {float(a.x()), float(a.y()), float(a.z())});
  return data;
}

void posedBodyMesh(const SkinnedMesh& body, const PoseData& data, Pose& pose,
                   std::vector<Eigen::Affine3f>& transforms, Eigen::Matrix3Xf& positions,
                   Eigen::Matrix3Xf& normals) {
  poseFromMessage(data, body.skeleton.jointCount(), pose);
  body.skeleton.skinningTransforms(pose, transforms);
  skinMesh(body, transforms, positions, normals);
  if (data.scale != 1.0f) positions *= data.scale;
}

}  // namespace lumistage
