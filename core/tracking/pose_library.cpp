#include "core/tracking/pose_library.h"

#include <Eigen/Geometry>
#include <cmath>
#include <utility>

#include "core/body/human_skeleton.h"
#include "core/body/motion_library.h"

namespace lumistage {

namespace {

Eigen::Matrix3d rotationOf(const Eigen::Vector3d& v) {
  const double a = v.norm();
  return a > 0 ? Eigen::AngleAxisd(a, v / a).toRotationMatrix() : Eigen::Matrix3d::Identity();
}

Eigen::Vector3d rotationVector(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.angle() * aa.axis();
}

double meanJointDistance(const std::vector<Eigen::Vector3d>& a,
                         const std::vector<Eigen::Vector3d>& b) {
  double sum = 0;
  for (size_t j = 0; j < a.size(); ++j) sum += (a[j] - b[j]).norm();
  return sum / double(a.size());
}

}  // namespace

Pose mirroredPose(const Pose& pose) {
  Pose out = pose;
  const auto flip = [](const Eigen::Vector3d& a) { return Eigen::Vector3d(a.x(), -a.y(), -a.z()); };
  for (size_t j = 0; j < pose.angles_rad.size(); ++j) out.angles_rad[j] = flip(pose.angles_rad[j]);
  const auto swap = [&](int right, int left, int count) {
    for (int k = 0; k < count; ++k)
      std::swap(out.angles_rad[size_t(right + k)], out.angles_rad[size_t(left + k)]);
  };
  if (int(out.angles_rad.size()) == kHumanJointCount) {
    swap(kRightClavicle, kLeftClavicle, 5);
    swap(kRightHip, kLeftHip, 4);
  }
  out.root_translation_m.x() = -pose.root_translation_m.x();
  return out;
}

Pose uprightFacingForward(const Pose& pose) {
  Pose out = pose;
  if (out.angles_rad.empty()) return out;
  const Eigen::Matrix3d r = rotationOf(pose.angles_rad[0]);
  const Eigen::Vector3d forward = r * Eigen::Vector3d::UnitY();
  const double heading = std::atan2(-forward.x(), forward.y());  // about +z, from +y
  out.angles_rad[0] =
      rotationVector(Eigen::AngleAxisd(-heading, Eigen::Vector3d::UnitZ()).toRotationMatrix() * r);
  out.root_translation_m.x() = out.root_translation_m.y() = 0;
  return out;
}

std::vector<Pose> makeInitialisationPoses(const Skeleton& skeleton, double min_spacing_m) {
  constexpr double kFps = 10, kSeconds = 4;
  std::vector<Pose> candidates = {Pose::rest(skeleton.jointCount())};
  for (const std::string& name : builtinClipNames()) {
    const MotionClip clip = makeBuiltinClip(name, skeleton, kFps, kSeconds);
    for (const Pose& p : clip.frames) {
      candidates.push_back(uprightFacingForward(p));
      candidates.push_back(mirroredPose(candidates.back()));
    }
  }
  std::vector<Pose> kept;
  std::vector<std::vector<Eigen::Vector3d>> kept_joints;
  std::vector<Eigen::Vector3d> joints;
  for (const Pose& p : candidates) {
    skeleton.jointPositions(p, joints);
    bool near = false;
    for (const auto& other : kept_joints)
      if (meanJointDistance(joints, other) < min_spacing_m) {
        near = true;
        break;
      }
    if (near) continue;
    kept.push_back(p);
    kept_joints.push_back(joints);
  }
  return kept;
}

}  // namespace lumistage
