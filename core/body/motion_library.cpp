#include "core/body/motion_library.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "core/body/human_skeleton.h"

namespace lumistage {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2 * kPi;
// Trackers initialise from the T-pose, so every clip leaves it smoothly over this time.
constexpr double kBlendSeconds = 0.5;
// Shoulder angle (about the forward axis) of the arms' carriage: hanging about 20 degrees out.
constexpr double kArmsDown = 1.2;
// Reference leg length (hip to ankle) of the 1.75 m generic body; distances a body covers with its
// legs (steps) scale with its own leg length.
constexpr double kReferenceLegM = 0.84;

double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

double smootherstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * x * (x * (6 * x - 15) + 10);
}

// A smooth periodic pulse of height 1 at `center` (radians); a higher sharpness makes it narrower.
double pulse(double phase, double center, double sharpness) {
  return std::exp(sharpness * (std::cos(phase - center) - 1));
}

double blendIn(double t) {
  return smoothstep(t / kBlendSeconds);
}

// Everything a clip's pose function needs besides the time.
struct ClipContext {
  const Skeleton& skeleton;
  double duration_s = 0;
  double leg_m = 0;      // hip to ankle
  double leg_scale = 1;  // leg_m / kReferenceLegM
  // Points of the sole in the ankle's (rest-aligned) frame: the heel and the ball of the foot. At
  // rest both lie on the floor (z = 0).
  std::array<Eigen::Vector3d, 2> sole;
};

Eigen::Vector3d& at(Pose& pose, HumanJoint joint) {
  return pose.angles_rad[joint];
}

// Both arms hang down to the side by `weight` (0: T-pose, 1: carriage). Right and left mirror the
// shoulder's y angle.
void lowerArms(Pose& pose, double weight, double angle = kArmsDown) {
  at(pose, kRightShoulder).y() = weight * angle;
  at(pose, kLeftShoulder).y() = -weight * angle;
}

Eigen::Vector3d bodyToWorld(double yaw, double right_m, double forward_m) {
  // The actor's right is +x and forward +y at yaw 0.
  return {right_m * std::cos(yaw) - forward_m * std::sin(yaw),
          right_m * std::sin(yaw) + forward_m * std::cos(yaw), 0};
}

// --- the clips: each sets the angles, root rotation and horizontal root translation -------------

void walkPose(const ClipContext& c, double t, Pose& pose) {
  constexpr double kCycleS = 1.1;
  constexpr double kEntryRadius = 0.3;   // the half circle from the stage centre onto the circle
  constexpr double kCircleRadius = 0.6;  // entered at (0.6, 0), walked clockwise seen from above
  const double a = blendIn(t);
  // A relaxed walk: two steps of 0.45 m per cycle (0.8 m/s); longer steps at this cadence swing
  // the feet faster than the smoothness bound of the clips allows.
  const double cycle_m = 0.9 * c.leg_scale;
  // Longer legs swing slower (a pendulum): the cadence scales with 1/sqrt(leg length).
  const double speed = cycle_m / (kCycleS * std::sqrt(c.leg_scale));
  // Distance walked: the speed ramps up with the blend (the integral of the smoothstep).
  const double u = std::min(t / kBlendSeconds, 1.0);
  const double s = t < kBlendSeconds ? speed * kBlendSeconds * (u * u * u - u * u * u * u / 2)
                                     : speed * (kBlendSeconds / 2 + t - kBlendSeconds);
  // Path: a half circle to the right from the centre (facing +y at the start) joins the circle
  // tangentially; yaw faces along the path.
  double x = 0, y = 0, yaw = 0;
  const double entry_m = kPi * kEntryRadius;
  if (s < entry_m) {
    const double b = s / kEntryRadius;
    x = kEntryRadius * (1 - std::cos(b));
    y = kEntryRadius * std::sin(b);
    yaw = -b;
  } else {
    const double g = (s - entry_m) / kCircleRadius;
    x = kCircleRadius * std::cos(g);
    y = -kCircleRadius * std::sin(g);
    yaw = -kPi - g;
  }
  // Gait phase follows the distance so the steps match the speed while it ramps. Phase 0: right
  // heel strike; the left leg is half a cycle later.
  const double phase = kTwoPi * s / cycle_m;
  for (int side = 0; side < 2; ++side) {
    const double p = phase + side * kPi;
    const double hip = 0.1 + 0.26 * std::cos(p + 0.1 * kTwoPi);  // most flexed late in swing
    // Knee: a small flexion absorbing the load early in stance, a large one in swing.
    const double knee =
        0.08 + 0.15 * pulse(p, 0.15 * kTwoPi, 10) + 0.85 * pulse(p, 0.7 * kTwoPi, 2.5);
    // Ankle: plantar flexion after heel strike and at push-off, dorsiflexion in mid stance and
    // swing (toe clearance).
    const double ankle = 0.12 * pulse(p, 0.42 * kTwoPi, 6) - 0.3 * pulse(p, 0.62 * kTwoPi, 8) -
                         0.08 * pulse(p, 0.07 * kTwoPi, 14) + 0.2 * pulse(p, 0.8 * kTwoPi, 8);
    at(pose, side == 0 ? kRightHip : kLeftHip).x() = a * hip;
    at(pose, side == 0 ? kRightKnee : kLeftKnee).x() = -a * knee;
    at(pose, side == 0 ? kRightAnkle : kLeftAnkle).x() = a * ankle;
  }
  const double right_forward = std::cos(phase + 0.1 * kTwoPi);  // 1: right thigh forward
  // Arms swing against the legs, elbows bend more as the arm comes forward.
  lowerArms(pose, a);
  at(pose, kRightShoulder).x() = -0.3 * a * right_forward;
  at(pose, kLeftShoulder).x() = 0.3 * a * right_forward;
  at(pose, kRightElbow).z() = a * (0.3 - 0.12 * right_forward);
  at(pose, kLeftElbow).z() = -a * (0.3 + 0.12 * right_forward);
  // The pelvis turns with the forward thigh, the thorax against it; the head looks ahead.
  const double twist = 0.08 * a * right_forward;
  for (HumanJoint spine : {kSpine1, kSpine2, kSpine3})
    at(pose, spine).z() = -0.035 * a * right_forward;
  at(pose, kSpine1).x() = -0.05 * a;  // a slight forward lean
  at(pose, kNeck).z() = 0.025 * a * right_forward;
  // The pelvis sways over the standing leg.
  const double sway = 0.025 * a * std::sin(phase - 0.05 * kTwoPi);
  pose.root_translation_m = Eigen::Vector3d(x, y, 0) + bodyToWorld(yaw, sway, 0);
  pose.angles_rad[0] = Eigen::Vector3d(0, 0, yaw + twist);
}

void armWavePose(const ClipContext& c, double t, Pose& pose) {
  const double a = blendIn(t);
  // Right arm: the shoulder twists the upper arm about its length by almost 90 degrees, which
  // turns elbow flexion (about z) into the frontal plane; its z then raises the upper arm a
  // little and the elbow holds the forearm up, waving about the vertical.
  const double wave = std::sin(kTwoPi * 1.6 * t);
  const double wave_weight = smoothstep((t - 0.3) / 0.6);
  at(pose, kRightShoulder) = a * Eigen::Vector3d(1.4, 0, 0.3);
  at(pose, kRightElbow).z() = a * 1.25 + 0.35 * wave_weight * wave;
  at(pose, kRightWrist).z() = 0.25 * wave_weight * std::sin(kTwoPi * 1.6 * t - 0.8);
  // Left arm by the side, slightly forward and bent.
  at(pose, kLeftShoulder) = a * Eigen::Vector3d(0.05, -kArmsDown, -0.1);
  at(pose, kLeftElbow).z() = -0.2 * a;
  at(pose, kHead).z() = -0.15 * a;  // looking a little towards the waving hand
  // Weight shift: the pelvis moves sideways, the legs tilt so that the feet stay put and flat.
  const double shift_m = 0.035 * a * std::sin(kTwoPi * t / 3.0);
  const double tilt = std::asin(shift_m / c.leg_m);
  for (HumanJoint hip : {kRightHip, kLeftHip}) at(pose, hip).y() = tilt;
  for (HumanJoint ankle : {kRightAnkle, kLeftAnkle}) at(pose, ankle).y() = -tilt;
  at(pose, kSpine1).y() = -0.5 * tilt;  // the torso leans back over the feet
  pose.root_translation_m = Eigen::Vector3d(shift_m, 0, 0);
}

void turnPose(const ClipContext& c, double t, Pose& pose) {
  constexpr double kStart = 0.15, kStepS = 0.9;
  const double a = blendIn(t);
  const double span = std::max(c.duration_s - kStart - 0.45, 0.1);
  const double u = std::clamp((t - kStart) / span, 0.0, 1.0);
  const double yaw = kTwoPi * smootherstep(u);
  // Small steps while turning: their size follows the turning speed (1 at its fastest).
  const double activity = 16 * u * u * (1 - u) * (1 - u);
  const double phase = kTwoPi * (t - kStart) / kStepS;
  for (int side = 0; side < 2; ++side) {
    const double lift =
        activity * std::pow(std::max(0.0, side == 0 ? std::sin(phase) : -std::sin(phase)), 2);
    at(pose, side == 0 ? kRightHip : kLeftHip).x() = 0.35 * lift;
    at(pose, side == 0 ? kRightKnee : kLeftKnee).x() = -0.7 * lift;
    at(pose, side == 0 ? kRightAnkle : kLeftAnkle).x() = 0.3 * lift;
  }
  lowerArms(pose, a);
  at(pose, kRightElbow).z() = 0.15 * a;
  at(pose, kLeftElbow).z() = -0.15 * a;
  at(pose, kNeck).z() = 0.2 * activity;  // the head leads the turn
  // The pelvis moves over the standing foot.
  pose.root_translation_m = bodyToWorld(yaw, -0.03 * activity * std::sin(phase), 0);
  pose.angles_rad[0] = Eigen::Vector3d(0, 0, yaw);
}

void crouchPose(const ClipContext& c, double t, Pose& pose) {
  constexpr double kStart = 0.4;
  const double a = blendIn(t);
  const double span = std::max(c.duration_s - kStart - 0.1, 0.1);
  const double u = std::clamp((t - kStart) / span, 0.0, 1.0);
  const double d = 0.5 * (1 - std::cos(2 * kTwoPi * u));  // depth 0..1, down and up twice
  // The feet stay flat: pelvis pitch + hip + knee + ankle flexion sum to zero.
  // The pelvis tips forward so that the torso leans over the feet: the hips go back behind the
  // heels, the shoulders come forward.
  const double pitch = -0.55 * d, knee = -1.85 * d, ankle = 0.45 * d;
  const double hip = -(pitch + knee + ankle);
  for (int side = 0; side < 2; ++side) {
    at(pose, side == 0 ? kRightHip : kLeftHip).x() = hip;
    at(pose, side == 0 ? kRightKnee : kLeftKnee).x() = knee;
    at(pose, side == 0 ? kRightAnkle : kLeftAnkle).x() = ankle;
  }
  at(pose, kSpine1).x() = -0.1 * d;
  at(pose, kSpine2).x() = -0.05 * d;
  at(pose, kNeck).x() = 0.4 * d;  // keeps looking ahead
  at(pose, kHead).x() = 0.3 * d;
  // Arms reach forward for balance as the body goes down.
  lowerArms(pose, 1.0, a * kArmsDown + 0.25 * d);
  at(pose, kRightShoulder).x() = 1.35 * d;
  at(pose, kLeftShoulder).x() = 1.35 * d;
  at(pose, kRightElbow).z() = 0.1 * a;
  at(pose, kLeftElbow).z() = -0.1 * a;
  pose.angles_rad[0] = Eigen::Vector3d(pitch, 0, 0);
}

void aPoseHoldPose(const ClipContext&, double t, Pose& pose) {
  constexpr double kAPose = 0.75;
  lowerArms(pose, smoothstep(t / 1.0), kAPose);
  // Breathing, so the hold is not a frozen frame.
  at(pose, kSpine3).x() = 0.02 * blendIn(t) * std::sin(kTwoPi * t / 4.0);
}

using PoseFunction = void (*)(const ClipContext&, double, Pose&);

struct ClipKind {
  const char* name;
  PoseFunction pose;
  bool anchor_feet;  // standing clips keep the feet where the rest pose has them
};

constexpr std::array<ClipKind, 5> kClips = {{{"walk", walkPose, false},
                                             {"arm_wave", armWavePose, true},
                                             {"turn", turnPose, false},
                                             {"crouch", crouchPose, true},
                                             {"a_pose_hold", aPoseHoldPose, true}}};

std::string validNames() {
  std::string list;
  for (const ClipKind& clip : kClips) list += std::string(list.empty() ? "" : ", ") + clip.name;
  return list;
}

void checkHumanSkeleton(const Skeleton& skeleton) {
  static const Skeleton reference = makeHumanSkeleton();
  if (skeleton.jointCount() != reference.jointCount()) {
    throw std::invalid_argument("motion clips need the " + std::to_string(reference.jointCount()) +
                                "-joint human skeleton; this skeleton has " +
                                std::to_string(skeleton.jointCount()) + " joints");
  }
  for (int j = 0; j < reference.jointCount(); ++j) {
    if (skeleton.joint(j).name != reference.joint(j).name) {
      throw std::invalid_argument("motion clips need the human skeleton: joint " +
                                  std::to_string(j) + " is '" + skeleton.joint(j).name +
                                  "', expected '" + reference.joint(j).name + "'");
    }
  }
}

// Moves the root horizontally so that the ankles' midpoint is where the rest pose has it.
void anchorFeet(const Skeleton& skeleton, Pose& pose, std::vector<Eigen::Isometry3d>& global) {
  skeleton.forwardKinematics(pose, global);
  const auto& rest = skeleton.restPositions();
  const Eigen::Vector3d error =
      0.5 * (global[kRightAnkle].translation() + global[kLeftAnkle].translation() -
             rest[kRightAnkle] - rest[kLeftAnkle]);
  pose.root_translation_m.x() -= error.x();
  pose.root_translation_m.y() -= error.y();
}

// Sets the root height so that the lowest point of either sole touches the floor.
void placeOnFloor(const ClipContext& c, Pose& pose, std::vector<Eigen::Isometry3d>& global) {
  c.skeleton.forwardKinematics(pose, global);
  double lowest = std::numeric_limits<double>::infinity();
  for (HumanJoint ankle : {kRightAnkle, kLeftAnkle}) {
    for (const Eigen::Vector3d& point : c.sole)
      lowest = std::min(lowest, (global[ankle] * point).z());
  }
  pose.root_translation_m.z() -= lowest;
}

}  // namespace

std::vector<std::string> builtinClipNames() {
  std::vector<std::string> names;
  for (const ClipKind& clip : kClips) names.emplace_back(clip.name);
  return names;
}

MotionClip makeBuiltinClip(std::string_view name, const Skeleton& skeleton, double fps,
                           double duration_s) {
  const auto kind =
      std::find_if(kClips.begin(), kClips.end(), [&](const ClipKind& k) { return name == k.name; });
  if (kind == kClips.end()) {
    throw std::invalid_argument("unknown motion clip '" + std::string(name) +
                                "'; the built-in clips are: " + validNames());
  }
  if (!(fps > 0) || !(duration_s > 0) || !std::isfinite(fps) || !std::isfinite(duration_s)) {
    throw std::invalid_argument("motion clip '" + std::string(name) +
                                "': fps and duration must be positive");
  }
  checkHumanSkeleton(skeleton);

  const auto& rest = skeleton.restPositions();
  ClipContext context{skeleton, duration_s, 0, 1, {}};
  context.leg_m = rest[kRightHip].z() - rest[kRightAnkle].z();
  context.leg_scale = context.leg_m / kReferenceLegM;
  // The rest pose stands on the floor: the ankle's height is the sole's depth below it.
  const double ankle_height = rest[kRightAnkle].z();
  const Eigen::Vector3d toe = skeleton.joint(kRightFoot).offset_m;
  context.sole = {Eigen::Vector3d(0, -0.25 * toe.y(), -ankle_height),
                  Eigen::Vector3d(0, toe.y(), -ankle_height)};

  MotionClip clip;
  clip.name = kind->name;
  clip.fps = fps;
  const auto frame_count = static_cast<size_t>(std::llround(duration_s * fps)) + 1;
  clip.frames.reserve(frame_count);
  std::vector<Eigen::Isometry3d> global;
  for (size_t i = 0; i < frame_count; ++i) {
    Pose pose = Pose::rest(skeleton.jointCount());
    kind->pose(context, double(i) / fps, pose);
    skeleton.clampToLimits(pose);
    if (kind->anchor_feet) anchorFeet(skeleton, pose, global);
    placeOnFloor(context, pose, global);
    clip.frames.push_back(std::move(pose));
  }
  return clip;
}

}  // namespace lumistage
