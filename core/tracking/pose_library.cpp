#include "core/tracking/pose_library.h"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <optional>
#include <utility>

#include "core/body/human_skeleton.h"
#include "core/body/motion_library.h"
#include "core/geometry/rotation.h"

namespace lumistage {

namespace {

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
  const Eigen::Matrix3d r = rotationFromVector(pose.angles_rad[0]);
  const Eigen::Vector3d forward = r * Eigen::Vector3d::UnitY();
  const double heading = std::atan2(-forward.x(), forward.y());  // about +z, from +y
  out.angles_rad[0] = rotationVectorOf(
      Eigen::AngleAxisd(-heading, Eigen::Vector3d::UnitZ()).toRotationMatrix() * r);
  out.root_translation_m.x() = out.root_translation_m.y() = 0;
  return out;
}

namespace {

// `pose` with its root pitched by angle_rad about the body's left-right axis, whichever way brings
// the head forward (`forward`; else whichever does not); none when neither way does.
std::optional<Pose> pitched(const Skeleton& skeleton, const Pose& pose, double angle_rad,
                            bool forward) {
  std::vector<Eigen::Vector3d> joints;
  skeleton.jointPositions(pose, joints);
  const double head_y = joints[kHead].y();
  std::optional<Pose> out;
  for (const double sign : {1.0, -1.0}) {
    Pose p = pose;
    const Eigen::Matrix3d pitch =
        Eigen::AngleAxisd(sign * angle_rad, Eigen::Vector3d::UnitX()).toRotationMatrix();
    p.angles_rad[0] = rotationVectorOf(rotationFromVector(pose.angles_rad[0]) * pitch);
    skeleton.jointPositions(p, joints);
    if ((joints[kHead].y() > head_y) == forward) out = p;
  }
  return out;
}

}  // namespace

Pose bentAtTheHips(const Skeleton& skeleton, const Pose& pose, double angle_rad) {
  // The torso pitched forward, each thigh turned back by as much so that the legs stand where
  // they stood.
  std::optional<Pose> bent = pitched(skeleton, pose, angle_rad, true);
  if (!bent) return pose;
  Pose& p = *bent;
  std::vector<Eigen::Vector3d> joints;
  for (const int hip : {int(kRightHip), int(kLeftHip)}) {
    const int ankle = hip + 2;
    double best_drift = 1e9;
    Pose chosen = p;
    for (const double turn : {1.0, -1.0}) {
      Pose q = p;
      q.angles_rad[size_t(hip)].x() += turn * angle_rad;
      skeleton.clampToLimits(q);
      skeleton.jointPositions(q, joints);
      const double drift = (joints[size_t(ankle)] - joints[size_t(hip)]).head<2>().norm();
      if (drift < best_drift) best_drift = drift, chosen = q;
    }
    p = chosen;
  }
  return p;
}

Pose sittingOnTheFloor(const Skeleton& skeleton, const Pose& arms, double lean_rad,
                       double knee_rad) {
  Pose p = arms;
  p.angles_rad[0] = Eigen::Vector3d::Zero();
  p.root_translation_m.x() = p.root_translation_m.y() = 0;
  for (const int j : {int(kSpine1), int(kSpine2), int(kSpine3), int(kNeck), int(kHead)})
    p.angles_rad[size_t(j)].setZero();
  // The torso leaned back (the root level: pitching it is leaning it).
  p = pitched(skeleton, p, lean_rad, false).value_or(p);
  std::vector<Eigen::Vector3d> joints;
  // Each thigh raised forward (whichever way brings the knee forward, as far as its limit allows),
  // above level by half the knee's bend so that the shin, bent down by knee_rad, brings the ankle
  // back to the hip's height: heels and seat on the floor.
  for (const int hip : {int(kRightHip), int(kLeftHip)}) {
    Pose best = p;
    double best_forward = -1e9;
    for (const double sign : {1.0, -1.0}) {
      Pose q = p;
      q.angles_rad[size_t(hip)].setZero();
      q.angles_rad[size_t(hip)].x() = sign * (0.5 * std::numbers::pi - lean_rad + 0.5 * knee_rad);
      q.angles_rad[size_t(hip + 1)] = Eigen::Vector3d(-knee_rad, 0, 0);
      q.angles_rad[size_t(hip + 2)].setZero();
      skeleton.clampToLimits(q);
      skeleton.jointPositions(q, joints);
      const double forward = joints[size_t(hip + 1)].y() - joints[size_t(hip)].y();
      if (forward > best_forward) best_forward = forward, best = q;
    }
    p = best;
  }
  return p;
}

std::vector<Pose> makeInitialisationPoses(const Skeleton& skeleton, double min_spacing_m) {
  constexpr double kFps = 10, kSeconds = 4;
  std::vector<Pose> candidates = {Pose::rest(skeleton.jointCount())};
  Pose a_pose = candidates[0];  // the A-pose clip's last frame: arms for the sitting poses
  for (const std::string& name : builtinClipNames()) {
    const MotionClip clip = makeBuiltinClip(name, skeleton, kFps, kSeconds);
    if (name == "a_pose_hold") a_pose = clip.frames.back();
    for (const Pose& p : clip.frames) {
      const Pose facing = uprightFacingForward(p);
      // Bent forward at the hips, as a body picking something up or leaning on a rail: the
      // clips never bend so far.
      for (const double bend : {0.0, 0.6, 1.2}) {
        candidates.push_back(bend > 0 ? bentAtTheHips(skeleton, facing, bend) : facing);
        candidates.push_back(mirroredPose(candidates.back()));
      }
    }
  }
  // Sitting on the floor, legs out or knees up, upright or leaning back on the hands: no clip
  // sits, and a body that sat down is found again only from a pose like his. (Each is its own
  // mirror image.)
  for (const Pose& arms : {candidates[0], a_pose})
    for (const double lean : {0.0, 0.4})
      for (const double knee : {0.0, 1.2, 2.2})
        candidates.push_back(sittingOnTheFloor(skeleton, arms, lean, knee));
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
