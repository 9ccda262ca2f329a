#include "core/body/skeleton.h"

#include <gtest/gtest.h>

#include <numbers>

#include "core/body/human_skeleton.h"
#include "core/body/skinned_mesh.h"

namespace lumistage {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(Skeleton, HumanSkeletonHasTheJointsOfTheDesign) {
  const Skeleton s = makeHumanSkeleton();
  EXPECT_EQ(s.jointCount(), 24);
  for (const char* name : {"pelvis", "spine1", "spine2", "spine3", "neck", "head", "left_clavicle",
                           "right_shoulder", "left_elbow", "right_wrist", "left_hand", "right_hip",
                           "left_knee", "right_ankle", "left_foot"}) {
    EXPECT_TRUE(s.findJoint(name)) << name;
  }
  // T-pose: wrists level with the shoulders, right arm along +x, feet near the floor.
  const auto& rest = s.restPositions();
  EXPECT_NEAR(rest[kRightWrist].z(), rest[kRightShoulder].z(), 1e-12);
  EXPECT_GT(rest[kRightWrist].x(), 0.6);
  EXPECT_LT(rest[kLeftWrist].x(), -0.6);
  EXPECT_NEAR(rest[kRightAnkle].z(), 0.08, 1e-12);
  // A taller body scales.
  BodyShape tall;
  tall.height_m = 1.75 * 1.15;
  EXPECT_NEAR(makeHumanSkeleton(tall).restPositions()[kHead].z(), 1.15 * rest[kHead].z(), 1e-9);
}

TEST(Skeleton, ForwardKinematicsOfAKnownPose) {
  const Skeleton s = makeHumanSkeleton();
  Pose pose = Pose::rest(s.jointCount());
  // Bend the right elbow 90 degrees: the forearm points forward (+y).
  pose.angles_rad[kRightElbow] = Eigen::Vector3d(0, 0, kPi / 2);
  std::vector<Eigen::Vector3d> p;
  s.jointPositions(pose, p);
  const auto& rest = s.restPositions();
  const double forearm = (rest[kRightWrist] - rest[kRightElbow]).norm();
  EXPECT_LT((p[kRightWrist] - (rest[kRightElbow] + Eigen::Vector3d(0, forearm, 0))).norm(), 1e-12);
  // Turn the whole body 90 degrees about z and lift it 10 cm: the right hand now points to +y.
  pose = Pose::rest(s.jointCount());
  pose.angles_rad[0] = Eigen::Vector3d(0, 0, kPi / 2);
  pose.root_translation_m = Eigen::Vector3d(0, 0, 0.1);
  s.jointPositions(pose, p);
  const Eigen::Vector3d from_pelvis = rest[kRightHand] - rest[kPelvis];
  const Eigen::Vector3d expected =
      rest[kPelvis] + Eigen::Vector3d(0, 0, 0.1) +
      Eigen::Vector3d(-from_pelvis.y(), from_pelvis.x(), from_pelvis.z());
  EXPECT_LT((p[kRightHand] - expected).norm(), 1e-12);
}

TEST(Skeleton, ClampKeepsAnglesInsideLimitsAndRejectsBadSkeletons) {
  const Skeleton s = makeHumanSkeleton();
  Pose pose = Pose::rest(s.jointCount());
  pose.angles_rad[kRightKnee] = Eigen::Vector3d(1.0, 0.5, -0.5);  // a knee bends one way only
  pose.angles_rad[0] = Eigen::Vector3d(3, 0, 0);                  // the root is free
  s.clampToLimits(pose);
  EXPECT_EQ(pose.angles_rad[kRightKnee], Eigen::Vector3d::Zero());
  EXPECT_EQ(pose.angles_rad[0], Eigen::Vector3d(3, 0, 0));
  EXPECT_THROW(Skeleton({{"a", -1, {0, 0, 0}, {}}, {"b", 5, {0, 0, 1}, {}}}),
               std::invalid_argument);
  EXPECT_THROW(Skeleton({{"a", -1, {0, 0, 0}, {}}, {"a", 0, {0, 0, 1}, {}}}),
               std::invalid_argument);
}

TEST(Skinning, MatchesHandComputedVertices) {
  // Two joints: root at the origin and a child 1 m up; vertex 0 fully on the child, vertex 1
  // half and half, vertex 2 on the root.
  SkinnedMesh mesh;
  JointLimits free{Eigen::Vector3d::Constant(-kPi), Eigen::Vector3d::Constant(kPi)};
  mesh.skeleton = Skeleton({{"root", -1, {0, 0, 0}, {}}, {"child", 0, {0, 0, 1}, free}});
  mesh.rest.positions.resize(3, 3);
  mesh.rest.positions << 0, 0, 0.5,  //
      0, 0, 0,                       //
      2, 1, 0.5;
  mesh.rest.normals = Eigen::Matrix3Xf::Zero(3, 3);
  mesh.rest.normals.row(1).setOnes();  // all facing +y
  mesh.skin.joints = {{1, 0, 0, 0}, {1, 0, 0, 0}, {0, 0, 0, 0}};
  mesh.skin.weights = {{1, 0, 0, 0}, {0.5f, 0.5f, 0, 0}, {1, 0, 0, 0}};
  mesh.validate();

  Pose pose = Pose::rest(2);
  pose.angles_rad[1] = Eigen::Vector3d(kPi / 2, 0, 0);  // child turns 90 degrees about x
  std::vector<Eigen::Affine3f> transforms;
  mesh.skeleton.skinningTransforms(pose, transforms);
  Eigen::Matrix3Xf positions, normals;
  skinMesh(mesh, transforms, positions, normals);
  // Vertex 0 at (0,0,2) is 1 m above the child: Rx(90) takes (0,0,1) to (0,-1,0), so (0,-1,1).
  EXPECT_LT((positions.col(0) - Eigen::Vector3f(0, -1, 1)).norm(), 1e-6);
  // Vertex 1 at (0,0,1) sits on the child joint: both transforms leave it there.
  EXPECT_LT((positions.col(1) - Eigen::Vector3f(0, 0, 1)).norm(), 1e-6);
  EXPECT_LT((positions.col(2) - Eigen::Vector3f(0.5, 0, 0.5)).norm(), 1e-6);
  // Normals: +y turns to +z on the child; half-blended gives (0, 1, 1)/sqrt(2); root keeps +y.
  EXPECT_LT((normals.col(0) - Eigen::Vector3f(0, 0, 1)).norm(), 1e-6);
  EXPECT_LT((normals.col(1) - Eigen::Vector3f(0, 1, 1).normalized()).norm(), 1e-6);
  EXPECT_LT((normals.col(2) - Eigen::Vector3f(0, 1, 0)).norm(), 1e-6);
}

TEST(Skinning, ValidateNamesTheBadVertex) {
  SkinnedMesh mesh;
  mesh.skeleton = Skeleton({{"root", -1, {0, 0, 0}, {}}});
  mesh.rest.positions = Eigen::Matrix3Xf::Zero(3, 1);
  mesh.rest.normals = Eigen::Matrix3Xf::Zero(3, 1);
  mesh.skin.joints = {{0, 0, 0, 0}};
  mesh.skin.weights = {{0.7f, 0, 0, 0}};
  try {
    mesh.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("weights of vertex 0 sum to 0.7"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace lumistage
