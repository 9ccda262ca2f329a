#include "core/body/skeleton.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lumistage {

Pose Pose::rest(int joint_count) {
  Pose pose;
  pose.angles_rad.assign(joint_count, Eigen::Vector3d::Zero());
  return pose;
}

Eigen::Matrix3d eulerRotation(const Eigen::Vector3d& a) {
  return (Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX()) *
          Eigen::AngleAxisd(a.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(a.z(), Eigen::Vector3d::UnitZ()))
      .toRotationMatrix();
}

Eigen::Vector3d eulerAnglesOf(const Eigen::Matrix3d& r) {
  const double sb = std::clamp(r(0, 2), -1.0, 1.0);
  const double b = std::asin(sb);
  if (std::abs(sb) > 1 - 1e-12) return {std::atan2(r(2, 1), r(1, 1)), b, 0.0};
  return {std::atan2(-r(1, 2), r(2, 2)), b, std::atan2(-r(0, 1), r(0, 0))};
}

Eigen::Matrix3d yUpToOurs() {
  Eigen::Matrix3d c;
  c << -1, 0, 0,  //
      0, 0, 1,    //
      0, 1, 0;
  return c;
}

Skeleton::Skeleton(std::vector<Joint> joints) : joints_(std::move(joints)) {
  if (joints_.empty()) throw std::invalid_argument("skeleton: no joints");
  rest_positions_.resize(joints_.size());
  for (int j = 0; j < jointCount(); ++j) {
    const Joint& joint = joints_[j];
    if (joint.name.empty())
      throw std::invalid_argument("skeleton: joint " + std::to_string(j) + " has no name");
    for (int k = 0; k < j; ++k) {
      if (joints_[k].name == joint.name) {
        throw std::invalid_argument("skeleton: joint name '" + joint.name + "' is used twice");
      }
    }
    if (j == 0 && joint.parent != -1) {
      throw std::invalid_argument("skeleton: the first joint ('" + joint.name +
                                  "') must be the root");
    }
    if (j > 0 && (joint.parent < 0 || joint.parent >= j)) {
      throw std::invalid_argument("skeleton: joint '" + joint.name +
                                  "' must have an earlier joint as parent (got index " +
                                  std::to_string(joint.parent) + ")");
    }
    if ((joint.limits.lower_rad.array() > joint.limits.upper_rad.array()).any()) {
      throw std::invalid_argument("skeleton: joint '" + joint.name +
                                  "' has a lower limit above its upper limit");
    }
    if (!joint.offset_m.allFinite()) {
      throw std::invalid_argument("skeleton: joint '" + joint.name + "' has a non-finite offset");
    }
    rest_positions_[j] = j == 0 ? joint.offset_m : rest_positions_[joint.parent] + joint.offset_m;
  }
}

std::optional<int> Skeleton::findJoint(std::string_view name) const {
  for (int j = 0; j < jointCount(); ++j) {
    if (joints_[j].name == name) return j;
  }
  return std::nullopt;
}

void Skeleton::forwardKinematics(const Pose& pose, std::vector<Eigen::Isometry3d>& global) const {
  if (global.size() != joints_.size()) global.resize(joints_.size());
  for (int j = 0; j < jointCount(); ++j) {
    const Eigen::Vector3d& a =
        j < static_cast<int>(pose.angles_rad.size()) ? pose.angles_rad[j] : Eigen::Vector3d::Zero();
    Eigen::Isometry3d local = Eigen::Isometry3d::Identity();
    if (j == 0) {
      const double angle = a.norm();
      if (angle > 0) local.linear() = Eigen::AngleAxisd(angle, a / angle).toRotationMatrix();
      local.translation() = joints_[0].offset_m + pose.root_translation_m;
      global[0] = local;
    } else {
      local.linear() = eulerRotation(a);
      local.translation() = joints_[j].offset_m;
      global[j] = global[joints_[j].parent] * local;
    }
  }
}

void Skeleton::jointPositions(const Pose& pose, std::vector<Eigen::Vector3d>& positions) const {
  std::vector<Eigen::Isometry3d> global;
  forwardKinematics(pose, global);
  positions.resize(global.size());
  for (size_t j = 0; j < global.size(); ++j) positions[j] = global[j].translation();
}

void Skeleton::skinningTransforms(const Pose& pose,
                                  std::vector<Eigen::Affine3f>& transforms) const {
  thread_local std::vector<Eigen::Isometry3d> global;
  forwardKinematics(pose, global);
  if (transforms.size() != global.size()) transforms.resize(global.size());
  // Rest frames are world-aligned, so the inverse rest transform is a translation by -rest.
  for (size_t j = 0; j < global.size(); ++j) {
    Eigen::Isometry3d m = global[j];
    m.translation() -= m.linear() * rest_positions_[j];
    transforms[j] = m.cast<float>();
  }
}

void Skeleton::clampToLimits(Pose& pose) const {
  for (int j = 1; j < jointCount() && j < static_cast<int>(pose.angles_rad.size()); ++j) {
    const JointLimits& l = joints_[j].limits;
    pose.angles_rad[j] = pose.angles_rad[j].cwiseMax(l.lower_rad).cwiseMin(l.upper_rad);
  }
}

}  // namespace lumistage
