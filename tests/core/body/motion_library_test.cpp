#include "core/body/motion_library.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "core/body/human_skeleton.h"

namespace lumistage {
namespace {

constexpr double kPi = std::numbers::pi;

std::vector<std::vector<Eigen::Vector3d>> framePositions(const Skeleton& skeleton,
                                                         const MotionClip& clip) {
  std::vector<std::vector<Eigen::Vector3d>> positions(clip.frames.size());
  for (size_t i = 0; i < clip.frames.size(); ++i) {
    skeleton.jointPositions(clip.frames[i], positions[i]);
  }
  return positions;
}

// The properties every clip has, on any human skeleton.
void expectWellFormed(const Skeleton& skeleton, const MotionClip& clip) {
  SCOPED_TRACE(clip.name);
  ASSERT_FALSE(clip.frames.empty());
  // Starts in the rest T-pose; only the root height may be adjusted to the floor.
  const Pose& first = clip.frames.front();
  ASSERT_EQ(first.angles_rad.size(), size_t(skeleton.jointCount()));
  for (int j = 0; j < skeleton.jointCount(); ++j) {
    EXPECT_LT(first.angles_rad[j].norm(), 1e-9) << skeleton.joint(j).name;
  }
  EXPECT_LT(first.root_translation_m.head<2>().norm(), 1e-9);
  EXPECT_LT(std::abs(first.root_translation_m.z()), 0.01);

  const auto positions = framePositions(skeleton, clip);
  double max_step_m = 0, lowest_foot_min = 1e9, lowest_foot_max = -1e9;
  for (size_t i = 0; i < clip.frames.size(); ++i) {
    const Pose& pose = clip.frames[i];
    Pose clamped = pose;
    skeleton.clampToLimits(clamped);
    EXPECT_EQ(clamped, pose) << "frame " << i << " leaves the joint limits";
    EXPECT_LE(std::abs(pose.root_translation_m.x()), 1.0) << "frame " << i;
    EXPECT_LE(std::abs(pose.root_translation_m.y()), 1.0) << "frame " << i;
    const double lowest_foot = std::min(positions[i][kRightFoot].z(), positions[i][kLeftFoot].z());
    lowest_foot_min = std::min(lowest_foot_min, lowest_foot);
    lowest_foot_max = std::max(lowest_foot_max, lowest_foot);
    if (i > 0) {
      for (int j = 0; j < skeleton.jointCount(); ++j) {
        max_step_m = std::max(max_step_m, (positions[i][j] - positions[i - 1][j]).norm());
      }
    }
  }
  EXPECT_GE(lowest_foot_min, -0.02);
  EXPECT_LE(lowest_foot_max, 0.06);
  EXPECT_LT(max_step_m, 0.15);
}

TEST(MotionLibrary, EveryClipStartsInTPoseStaysInLimitsOnStageOnTheFloorAndIsSmooth) {
  const Skeleton skeleton = makeHumanSkeleton();
  const std::vector<std::string> names = builtinClipNames();
  for (const char* required : {"walk", "arm_wave", "turn", "crouch"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), required), names.end()) << required;
  }
  for (const std::string& name : names) {
    const MotionClip clip = makeBuiltinClip(name, skeleton);
    EXPECT_EQ(clip.name, name);
    EXPECT_EQ(clip.fps, 30.0);
    EXPECT_EQ(clip.frames.size(), 121u);
    EXPECT_NEAR(clip.durationSeconds(), 4.0, 1e-12);
    expectWellFormed(skeleton, clip);
  }
}

TEST(MotionLibrary, ClipsFitAScaledSkeleton) {
  BodyShape tall;
  tall.height_m = 2.0;
  const Skeleton skeleton = makeHumanSkeleton(tall);
  EXPECT_GT(skeleton.restPositions()[kHead].z(),
            1.1 * makeHumanSkeleton().restPositions()[kHead].z());
  for (const std::string& name : builtinClipNames()) {
    SCOPED_TRACE(name);
    expectWellFormed(skeleton,
                     makeBuiltinClip(name, skeleton));  // feet on the floor, limits, smooth
  }
  BodyShape long_legs;
  long_legs.leg_length_scale = 1.15;
  const Skeleton other = makeHumanSkeleton(long_legs);
  for (const std::string& name : builtinClipNames()) {
    expectWellFormed(other, makeBuiltinClip(name, other, 30.0, 6.0));
  }
}

TEST(MotionLibrary, ArmsComeDownToACarriage) {
  // Past the blend, no clip holds the arms out level like the T-pose (except waving hello).
  const Skeleton skeleton = makeHumanSkeleton();
  for (const char* name : {"walk", "turn", "crouch"}) {
    const MotionClip clip = makeBuiltinClip(name, skeleton);
    const Pose& pose = clip.frames[30];  // 1 s in
    EXPECT_NEAR(pose.angles_rad[kRightShoulder].y(), 1.2, 0.3) << name;
    EXPECT_NEAR(pose.angles_rad[kLeftShoulder].y(), -1.2, 0.3) << name;
  }
}

TEST(MotionLibrary, WalkGoesRoundTheStage) {
  const Skeleton skeleton = makeHumanSkeleton();
  const MotionClip clip = makeBuiltinClip("walk", skeleton);
  const auto positions = framePositions(skeleton, clip);
  double path_m = 0, max_radius_m = 0;
  std::array<bool, 4> quadrants{};
  for (size_t i = 1; i < positions.size(); ++i) {
    const Eigen::Vector2d pelvis = positions[i][kPelvis].head<2>();
    path_m += (pelvis - positions[i - 1][kPelvis].head<2>()).norm();
    max_radius_m = std::max(max_radius_m, pelvis.norm());
    quadrants[(pelvis.x() < 0 ? 1 : 0) + (pelvis.y() < 0 ? 2 : 0)] = true;
  }
  EXPECT_GT(path_m, 2.0);
  EXPECT_GT(max_radius_m, 0.5);
  EXPECT_LT(max_radius_m, 0.7);
  // Round the centre: the pelvis passes through every quadrant of the stage.
  for (bool visited : quadrants) EXPECT_TRUE(visited);
  // The legs take turns: each foot is sometimes well above the other.
  double right_above = 0, left_above = 0;
  for (const auto& p : positions) {
    right_above = std::max(right_above, p[kRightAnkle].z() - p[kLeftAnkle].z());
    left_above = std::max(left_above, p[kLeftAnkle].z() - p[kRightAnkle].z());
  }
  EXPECT_GT(right_above, 0.08);
  EXPECT_GT(left_above, 0.08);
}

double facingAngle(const std::vector<Eigen::Vector3d>& p) {
  // The actor faces +y when its right (hip to hip) is +x.
  const Eigen::Vector3d right = p[kRightHip] - p[kLeftHip];
  return std::atan2(right.x(), -right.y());
}

TEST(MotionLibrary, TurnTurnsAFullCircle) {
  const Skeleton skeleton = makeHumanSkeleton();
  const auto positions = framePositions(skeleton, makeBuiltinClip("turn", skeleton));
  EXPECT_NEAR(facingAngle(positions.front()), kPi / 2, 1e-9);
  double turned = 0;
  std::array<bool, 4> quadrants{};
  for (size_t i = 1; i < positions.size(); ++i) {
    turned += std::remainder(facingAngle(positions[i]) - facingAngle(positions[i - 1]), 2 * kPi);
    const double facing = facingAngle(positions[i]);
    quadrants[(std::cos(facing) < 0 ? 1 : 0) + (std::sin(facing) < 0 ? 2 : 0)] = true;
    // On the spot.
    EXPECT_LT(positions[i][kPelvis].head<2>().norm(), 0.1);
  }
  EXPECT_NEAR(turned, 2 * kPi, 0.1);
  for (bool visited : quadrants) EXPECT_TRUE(visited);
}

TEST(MotionLibrary, CrouchGoesDownTwice) {
  const Skeleton skeleton = makeHumanSkeleton();
  const auto positions = framePositions(skeleton, makeBuiltinClip("crouch", skeleton));
  const double standing = skeleton.restPositions()[kPelvis].z();
  double lowest = standing;
  int descents = 0;
  bool down = false;
  for (const auto& p : positions) {
    lowest = std::min(lowest, p[kPelvis].z());
    if (!down && p[kPelvis].z() < standing - 0.25) {
      ++descents;
      down = true;
    } else if (down && p[kPelvis].z() > standing - 0.1) {
      down = false;
    }
  }
  EXPECT_GT(standing - lowest, 0.3);
  EXPECT_LT(standing - lowest, 0.5);
  EXPECT_EQ(descents, 2);
  // The feet stay where they stand.
  for (const auto& p : positions) {
    EXPECT_LT((p[kRightAnkle] - positions.front()[kRightAnkle]).head<2>().norm(), 0.03);
  }
}

TEST(MotionLibrary, ArmWaveRaisesAWristAboveTheHead) {
  const Skeleton skeleton = makeHumanSkeleton();
  const auto positions = framePositions(skeleton, makeBuiltinClip("arm_wave", skeleton));
  int raised = 0;
  double wrist_min_x = 1e9, wrist_max_x = -1e9;
  for (const auto& p : positions) {
    if (std::max(p[kRightWrist].z(), p[kLeftWrist].z()) > p[kHead].z()) {
      ++raised;
      wrist_min_x = std::min(wrist_min_x, p[kRightWrist].x());
      wrist_max_x = std::max(wrist_max_x, p[kRightWrist].x());
    }
  }
  EXPECT_GT(raised, int(positions.size()) / 2);
  EXPECT_GT(wrist_max_x - wrist_min_x, 0.1);  // it waves
}

TEST(MotionLibrary, RejectsUnknownNamesAndOtherSkeletons) {
  const Skeleton skeleton = makeHumanSkeleton();
  try {
    makeBuiltinClip("moonwalk", skeleton);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("moonwalk"), std::string::npos) << message;
    for (const std::string& name : builtinClipNames()) {
      EXPECT_NE(message.find(name), std::string::npos) << message;
    }
  }
  const Skeleton small({{"root", -1, {0, 0, 1}, {}}, {"tip", 0, {0, 0, 1}, {}}});
  EXPECT_THROW(makeBuiltinClip("walk", small), std::invalid_argument);
  std::vector<Joint> renamed = skeleton.joints();
  renamed[kLeftKnee].name = "left_knee_2";
  EXPECT_THROW(makeBuiltinClip("walk", Skeleton(renamed)), std::invalid_argument);
  EXPECT_THROW(makeBuiltinClip("walk", skeleton, 0.0), std::invalid_argument);
  EXPECT_THROW(makeBuiltinClip("walk", skeleton, 30.0, -1.0), std::invalid_argument);
}

}  // namespace
}  // namespace lumistage
