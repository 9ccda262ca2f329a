#include "core/body/human_skeleton.h"

#include <fmt/format.h>

namespace lumistage {

namespace {

JointLimits limits(Eigen::Vector3d lower, Eigen::Vector3d upper) {
  return {lower, upper};
}

}  // namespace

double statureOf(const BodyShape& shape) {
  // makeHumanSkeleton's head joint stands 0.71 s + 0.84 s legs high (s = height / 1.75), the crown
  // 0.20 s above it: 1.75 s for the generic legs.
  const double s = shape.height_m / 1.75;
  return s * (0.91 + 0.84 * shape.leg_length_scale);
}

Skeleton makeHumanSkeleton(const BodyShape& shape) {
  const double s = shape.height_m / 1.75;
  const double arm = s * shape.arm_length_scale, leg = s * shape.leg_length_scale;
  const double sw = s * shape.shoulder_width_scale, hw = s * shape.hip_width_scale;
  const double hip_z = 0.08 * s + 0.84 * leg;
  using V = Eigen::Vector3d;
  const JointLimits none;
  // Angles: x flexes about the lateral axis, y about the forward axis, z about the vertical (see
  // skeleton.h). Right and left limbs mirror each other in y and z.
  const JointLimits spine = limits({-0.5, -0.3, -0.4}, {0.3, 0.3, 0.4});
  std::vector<Joint> j(kHumanJointCount);
  j[kPelvis] = {"pelvis", -1, V(0, 0, hip_z + 0.03 * s), none};
  j[kSpine1] = {"spine1", kPelvis, V(0, 0, 0.10 * s), spine};
  j[kSpine2] = {"spine2", kSpine1, V(0, 0, 0.12 * s), spine};
  j[kSpine3] = {"spine3", kSpine2, V(0, 0, 0.13 * s), spine};
  j[kNeck] = {"neck", kSpine3, V(0, 0, 0.16 * s), limits({-0.6, -0.4, -0.7}, {0.5, 0.4, 0.7})};
  j[kHead] = {"head", kNeck, V(0, 0, 0.09 * s), limits({-0.4, -0.3, -0.5}, {0.4, 0.3, 0.5})};
  for (int side = 0; side < 2; ++side) {
    const double x = side == 0 ? 1.0 : -1.0;  // right is +x
    const int base = side == 0 ? kRightClavicle : kLeftClavicle;
    const char* name = side == 0 ? "right_" : "left_";
    auto mirror = [x](JointLimits l) {  // y and z ranges flip sign on the left
      if (x > 0) return l;
      return JointLimits{V(l.lower_rad.x(), -l.upper_rad.y(), -l.upper_rad.z()),
                         V(l.upper_rad.x(), -l.lower_rad.y(), -l.lower_rad.z())};
    };
    j[base + 0] = {std::string(name) + "clavicle", kSpine3, V(0.03 * x * sw, 0, 0.12 * s),
                   mirror(limits({-0.2, -0.3, -0.3}, {0.2, 0.3, 0.3}))};
    j[base + 1] = {std::string(name) + "shoulder", base + 0, V(0.15 * x * sw, 0, 0),
                   mirror(limits({-1.5, -1.2, -0.8}, {1.5, 1.5, 1.6}))};
    j[base + 2] = {std::string(name) + "elbow", base + 1, V(0.28 * x * arm, 0, 0),
                   mirror(limits({-1.0, 0.0, 0.0}, {1.0, 0.0, 2.5}))};
    j[base + 3] = {std::string(name) + "wrist", base + 2, V(0.25 * x * arm, 0, 0),
                   mirror(limits({-0.5, -0.6, -1.0}, {0.5, 0.6, 1.0}))};
    j[base + 4] = {std::string(name) + "hand", base + 3, V(0.09 * x * arm, 0, 0), none};

    const int leg_base = side == 0 ? kRightHip : kLeftHip;
    j[leg_base + 0] = {std::string(name) + "hip", kPelvis, V(0.09 * x * hw, 0, -0.03 * s),
                       mirror(limits({-0.5, -0.8, -0.6}, {2.0, 0.3, 0.6}))};
    j[leg_base + 1] = {std::string(name) + "knee", leg_base + 0, V(0, 0, -0.42 * leg),
                       limits({-2.4, 0, 0}, {0, 0, 0})};
    j[leg_base + 2] = {std::string(name) + "ankle", leg_base + 1, V(0, 0, -0.42 * leg),
                       limits({-0.7, -0.3, -0.3}, {0.5, 0.3, 0.3})};
    j[leg_base + 3] = {std::string(name) + "foot", leg_base + 2, V(0, 0.14 * s, -0.06 * s), none};
  }
  return Skeleton(std::move(j));
}

void checkHumanJointOrder(const Skeleton& skeleton, std::string_view source) {
  static const Skeleton human = makeHumanSkeleton();
  if (skeleton.jointCount() != human.jointCount()) {
    throw std::invalid_argument(fmt::format("{}: {} joints, the human skeleton has {}", source,
                                            skeleton.jointCount(), human.jointCount()));
  }
  for (int j = 0; j < human.jointCount(); ++j) {
    if (skeleton.joint(j).name == human.joint(j).name) continue;
    throw std::invalid_argument(fmt::format(
        "{}: joint {} is '{}' where the human skeleton has '{}': its joints must come in the "
        "human skeleton's order (pelvis, spine1..3, neck, head, then the right arm, the left arm, "
        "the right leg, the left leg)",
        source, j, skeleton.joint(j).name, human.joint(j).name));
  }
}

}  // namespace lumistage
