// Posing a skeleton to 3D joint targets, against targets of a known pose and scale.
#include "core/body/joint_pose_fit.h"

#include <gtest/gtest.h>

#include <random>

#include "core/body/human_model.h"
#include "core/body/human_skeleton.h"

namespace lumistage {
namespace {

TEST(JointPoseFit, RecoversAKnownPoseAndScale) {
  const Skeleton skeleton = makeHumanSkeleton();
  std::mt19937 rng(3);
  Pose truth = Pose::rest(skeleton.jointCount());
  truth.root_translation_m = {0.3, -0.2, 0.05};
  truth.angles_rad[0] = {0.05, -0.1, 0.8};
  std::uniform_real_distribution<double> u(0, 1);
  for (int j = 1; j < skeleton.jointCount(); ++j) {
    const JointLimits& l = skeleton.joint(j).limits;
    for (int a = 0; a < 3; ++a)
      truth.angles_rad[j][a] =
          l.lower_rad[a] + (0.25 + 0.5 * u(rng)) * (l.upper_rad[a] - l.lower_rad[a]);
  }
  const double scale = 1.06;
  std::vector<Eigen::Vector3d> targets;
  skeleton.jointPositions(truth, targets);
  for (auto& t : targets) t *= scale;

  const JointPoseFit fit =
      fitPoseToJoints(skeleton, targets, initialJointPoseFit(skeleton, targets));
  EXPECT_LT(fit.rms_m, 0.002);
  EXPECT_NEAR(fit.scale, scale, 0.01);
  std::vector<Eigen::Vector3d> fitted;
  skeleton.jointPositions(fit.pose, fitted);
  for (int j = 0; j < skeleton.jointCount(); ++j)
    EXPECT_LT((fit.scale * fitted[j] - targets[j]).norm(), 0.005) << skeleton.joint(j).name;
}

TEST(JointPoseFit, TheScaledMeshFollowsTheScaledJoints) {
  HumanModelSpec spec;
  spec.target_vertices = 600;
  const SkinnedMesh human = makeHumanModel(spec);
  std::vector<Eigen::Vector3d> targets;
  human.skeleton.jointPositions(Pose::rest(human.skeleton.jointCount()), targets);
  for (auto& t : targets) t = 1.1 * t + Eigen::Vector3d(0.5, 0, 0);
  const JointPoseFit fit =
      fitPoseToJoints(human.skeleton, targets, initialJointPoseFit(human.skeleton, targets));
  Eigen::Matrix3Xf positions, normals;
  posedScaledMesh(human, fit, positions, normals);
  for (int v = 0; v < human.rest.vertexCount(); v += 37) {
    const Eigen::Vector3f expected =
        1.1f * human.rest.positions.col(v) + Eigen::Vector3f(0.5f, 0, 0);
    EXPECT_LT((positions.col(v) - expected).norm(), 0.01f);
  }
}

TEST(JointPoseFit, RefusesTheWrongNumberOfTargets) {
  const Skeleton skeleton = makeHumanSkeleton();
  EXPECT_THROW(fitPoseToJoints(skeleton, std::vector<Eigen::Vector3d>(3), JointPoseFit{}),
               std::invalid_argument);
}

}  // namespace
}  // namespace lumistage
