#include "core/tracking/pose_library.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/body/human_skeleton.h"
#include "core/body/motion_library.h"

namespace lumistage {
namespace {

// The mirror image's joints are the pose's reflected through x = 0, and mirroring twice gives the
// pose back.
TEST(PoseLibrary, AMirroredPoseIsThePoseReflected) {
  const Skeleton skeleton = makeHumanSkeleton();
  const MotionClip wave = makeBuiltinClip("arm_wave", skeleton, 30, 3);
  std::vector<Eigen::Vector3d> joints, mirrored;
  for (double t : {0.7, 1.9}) {
    Pose p = wave.sample(t);
    p.root_translation_m += Eigen::Vector3d(0.3, -0.2, 0.05);
    skeleton.jointPositions(p, joints);
    skeleton.jointPositions(mirroredPose(p), mirrored);
    const auto reflected = [](Eigen::Vector3d v) {
      v.x() = -v.x();
      return v;
    };
    const auto partner = [](int j) {
      if (j >= kRightClavicle && j <= kRightHand) return j + 5;
      if (j >= kLeftClavicle && j <= kLeftHand) return j - 5;
      if (j >= kRightHip && j <= kRightFoot) return j + 4;
      if (j >= kLeftHip && j <= kLeftFoot) return j - 4;
      return j;
    };
    for (int j = 0; j < kHumanJointCount; ++j)
      EXPECT_LT((mirrored[partner(j)] - reflected(joints[j])).norm(), 1e-9)
          << skeleton.joint(j).name;
    const Pose twice = mirroredPose(mirroredPose(p));
    for (int j = 0; j < kHumanJointCount; ++j)
      EXPECT_LT((twice.angles_rad[j] - p.angles_rad[j]).norm(), 1e-12);
    // Within the limits: the left limbs' are the right ones' mirrored.
    Pose clamped = mirroredPose(p);
    skeleton.clampToLimits(clamped);
    for (int j = 1; j < kHumanJointCount; ++j)
      EXPECT_LT((clamped.angles_rad[j] - mirroredPose(p).angles_rad[j]).norm(), 1e-9)
          << skeleton.joint(j).name;
  }
}

TEST(PoseLibrary, PosesFaceForwardOverTheOriginAndDifferFromOneAnother) {
  const Skeleton skeleton = makeHumanSkeleton();
  const std::vector<Pose> poses = makeInitialisationPoses(skeleton, 0.04);
  ASSERT_GT(poses.size(), 20u);
  ASSERT_LT(poses.size(), 400u);
  EXPECT_EQ(poses[0], Pose::rest(kHumanJointCount));
  std::vector<std::vector<Eigen::Vector3d>> joints(poses.size());
  int crouched = 0, bent = 0, sitting = 0;
  for (size_t i = 0; i < poses.size(); ++i) {
    skeleton.jointPositions(poses[i], joints[i]);
    EXPECT_EQ(poses[i].root_translation_m.x(), 0);
    EXPECT_EQ(poses[i].root_translation_m.y(), 0);
    const Eigen::AngleAxisd root(poses[i].angles_rad[0].norm(),
                                 poses[i].angles_rad[0].norm() > 0
                                     ? Eigen::Vector3d(poses[i].angles_rad[0].normalized())
                                     : Eigen::Vector3d::UnitZ());
    const Eigen::Vector3d forward = root * Eigen::Vector3d::UnitY();
    EXPECT_NEAR(forward.x(), 0, 1e-9) << i;  // turned to face +y (pitched, never turned aside)
    crouched += joints[i][kPelvis].z() < joints[0][kPelvis].z() - 0.2;
    // Bent forward at the hips: the head ahead of the pelvis and lower than it stands.
    bent += joints[i][kHead].y() - joints[i][kPelvis].y() > 0.4 &&
            joints[i][kHead].z() < joints[0][kHead].z() - 0.3;
    // Sitting: both thighs forward, the ankles about as high as the hips.
    bool seated = true;
    for (const int hip : {int(kRightHip), int(kLeftHip)}) {
      const Eigen::Vector3d thigh = joints[i][size_t(hip + 1)] - joints[i][size_t(hip)];
      const double drop = joints[i][size_t(hip)].z() - joints[i][size_t(hip + 2)].z();
      seated = seated && thigh.y() > 0.15 && std::abs(drop) < 0.15;
    }
    sitting += seated;
    for (size_t k = 0; k < i; ++k) {
      double sum = 0;
      for (size_t j = 0; j < joints[i].size(); ++j) sum += (joints[i][j] - joints[k][j]).norm();
      EXPECT_GE(sum / joints[i].size(), 0.04) << i << " and " << k;
    }
  }
  EXPECT_GT(crouched, 2);
  EXPECT_GT(bent, 4);
  EXPECT_GE(sitting, 8);
}

// Sitting on the floor: heels and seat level, the head behind the hips by the lean, every angle
// within its limits.
TEST(PoseLibrary, ASittingPoseHasItsThighsForwardAndItsKneesBent) {
  const Skeleton skeleton = makeHumanSkeleton();
  std::vector<Eigen::Vector3d> joints, upright_joints;
  const Pose rest = Pose::rest(kHumanJointCount);
  skeleton.jointPositions(sittingOnTheFloor(skeleton, rest, 0.0, 1.2), upright_joints);
  for (const double knee : {0.0, 1.2}) {
    const Pose p = sittingOnTheFloor(skeleton, rest, 0.4, knee);
    Pose clamped = p;
    skeleton.clampToLimits(clamped);
    for (int j = 0; j < kHumanJointCount; ++j)
      EXPECT_LT((clamped.angles_rad[j] - p.angles_rad[j]).norm(), 1e-12) << skeleton.joint(j).name;
    skeleton.jointPositions(p, joints);
    for (const int hip : {int(kRightHip), int(kLeftHip)}) {
      const Eigen::Vector3d thigh = joints[size_t(hip + 1)] - joints[size_t(hip)];
      const Eigen::Vector3d shin = joints[size_t(hip + 2)] - joints[size_t(hip + 1)];
      // Raised forward by half the knee's bend, the shin turned down from its line by the bend:
      // the ankle back at the hip's height.
      EXPECT_NEAR(std::atan2(thigh.z(), thigh.y()), 0.5 * knee, 0.05);
      EXPECT_NEAR(std::acos(thigh.normalized().dot(shin.normalized())), knee, 0.05);
      EXPECT_NEAR(joints[size_t(hip + 2)].z(), joints[size_t(hip)].z(), 0.03);
    }
    // Leaned back: the head behind the pelvis, further than sitting upright.
    EXPECT_LT(joints[kHead].y() - joints[kPelvis].y(), -0.2);
    EXPECT_GT(joints[kHead].z(), joints[kPelvis].z() + 0.4);
  }
  EXPECT_NEAR(upright_joints[kHead].y(), upright_joints[kPelvis].y(), 0.02);
}

}  // namespace
}  // namespace lumistage
