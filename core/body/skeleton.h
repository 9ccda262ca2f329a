#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace lumistage {

// Body frame of every rest pose: metres, z up, the actor faces +y, so +x is the actor's right.
// Rest poses have no rotations: every joint's local frame is aligned with the world axes, which
// makes joint angles mean the same thing on every skeleton (and joint limits portable).

// Limits of a joint's three Euler angles (radians). A hinge has equal bounds on two axes; an end
// joint (hand, foot, head top) has all bounds zero.
struct JointLimits {
  Eigen::Vector3d lower_rad = Eigen::Vector3d::Zero();
  Eigen::Vector3d upper_rad = Eigen::Vector3d::Zero();
  bool operator==(const JointLimits&) const = default;
};

struct Joint {
  std::string name;
  int parent = -1;           // -1 for the root; otherwise an index lower than this joint's
  Eigen::Vector3d offset_m;  // rest position relative to the parent joint (the root: absolute)
  JointLimits limits;
  bool operator==(const Joint&) const = default;
};

// Pose parameterisation, chosen for fitting (Gauss-Newton / Levenberg-Marquardt):
// - the root (pelvis) has a translation and a rotation vector (axis x angle): unconstrained,
//   no gimbal lock for the whole body's orientation;
// - every other joint has three Euler angles (x, y, z), R = Rx·Ry·Rz in its rest frame, with box
//   limits per angle: limits are exact and cheap to enforce (clamp, or bounds in the solver),
//   and the ranges keep the middle angle within ±90°, away from gimbal lock.
struct Pose {
  Eigen::Vector3d root_translation_m = Eigen::Vector3d::Zero();  // added to the root's rest place
  std::vector<Eigen::Vector3d> angles_rad;  // per joint; [0] is the root's rotation vector

  static Pose rest(int joint_count);
  bool operator==(const Pose&) const = default;
};

Eigen::Matrix3d eulerRotation(const Eigen::Vector3d& angles_rad);  // Rx(a.x) Ry(a.y) Rz(a.z)
// Its inverse: the angles of R = Rx(a) Ry(b) Rz(c) with b in [-pi/2, pi/2]; at gimbal lock c = 0.
Eigen::Vector3d eulerAnglesOf(const Eigen::Matrix3d& r);

// The Y-up convention of BVH, glTF and Assimp (Y up, facing +Z, +X the actor's left) to ours (z
// up, facing +y, +x right): x = -X, y = Z, z = Y. A proper rotation and its own inverse, so the
// same matrix converts back.
Eigen::Matrix3d yUpToOurs();

class Skeleton {
 public:
  Skeleton() = default;
  // Throws std::invalid_argument naming the joint: empty or duplicate name, a parent that is not
  // an earlier joint, more than one root, lower limit above upper.
  explicit Skeleton(std::vector<Joint> joints);

  int jointCount() const { return static_cast<int>(joints_.size()); }
  const Joint& joint(int index) const { return joints_.at(index); }
  const std::vector<Joint>& joints() const { return joints_; }
  std::optional<int> findJoint(std::string_view name) const;
  const std::vector<Eigen::Vector3d>& restPositions() const { return rest_positions_; }

  // World transform of every joint for a pose (rest-aligned local frames). `global` is resized
  // only when its size differs: reuse it and the call does not allocate.
  void forwardKinematics(const Pose& pose, std::vector<Eigen::Isometry3d>& global) const;
  // Joint positions for a pose.
  void jointPositions(const Pose& pose, std::vector<Eigen::Vector3d>& positions) const;
  // Skinning transforms: rest-pose world coordinates to posed world coordinates, per joint.
  void skinningTransforms(const Pose& pose, std::vector<Eigen::Affine3f>& transforms) const;
  // Clamps every joint's Euler angles into its limits (the root is left free).
  void clampToLimits(Pose& pose) const;

  bool operator==(const Skeleton&) const = default;

 private:
  std::vector<Joint> joints_;
  std::vector<Eigen::Vector3d> rest_positions_;
};

}  // namespace lumistage
