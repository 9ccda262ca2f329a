#include "core/render/camera_path.h"

#include <gtest/gtest.h>

#include <cmath>

namespace lumistage {
namespace {

ViewPose poseAt(double yaw_rad, const Eigen::Vector3d& target = {0, 0, 1}) {
  OrbitView v;
  v.setTarget(target);
  v.set(yaw_rad, 0.2, 4.0);
  return v.pose();
}

TEST(CameraPath, PassesThroughItsKeys) {
  CameraPath path;
  path.setKey(2.0, poseAt(1.0));
  path.setKey(0.0, poseAt(0.0));
  path.setKey(5.0, poseAt(2.0));
  ASSERT_EQ(path.keys().size(), 3u);
  EXPECT_DOUBLE_EQ(path.keys()[1].time_s, 2.0);  // sorted
  EXPECT_DOUBLE_EQ(path.duration(), 5.0);
  for (const CameraKey& key : path.keys()) {
    const ViewPose p = path.at(key.time_s);
    EXPECT_LT((p.eye - key.pose.eye).norm(), 1e-9);
    EXPECT_LT(p.orientation.angularDistance(key.pose.orientation), 1e-9);
  }
  // Holds still outside the keys.
  EXPECT_LT((path.at(-1).eye - path.keys().front().pose.eye).norm(), 1e-12);
  EXPECT_LT((path.at(9).eye - path.keys().back().pose.eye).norm(), 1e-12);
}

TEST(CameraPath, TurnsAlongTheShortestArcAtAnEvenRate) {
  CameraPath path;
  ViewPose a = poseAt(0.0), b = poseAt(0.0);
  b.orientation =
      a.orientation * Eigen::Quaterniond(Eigen::AngleAxisd(1.2, Eigen::Vector3d::UnitY()));
  path.setKey(0, a);
  path.setKey(1, b);
  for (double u : {0.25, 0.5, 0.75}) {
    const ViewPose p = path.at(u);
    EXPECT_NEAR(p.orientation.angularDistance(a.orientation), 1.2 * u, 1e-9);
    EXPECT_NEAR(p.orientation.angularDistance(b.orientation), 1.2 * (1 - u), 1e-9);
    EXPECT_LT((p.eye - a.eye).norm(), 1e-12);  // the centre stays
  }
}

TEST(CameraPath, CentreMovesSmoothlyThroughTheKeys) {
  CameraPath path;
  for (int k = 0; k < 5; ++k) path.setKey(k, poseAt(0.5 * k));
  // Velocity is continuous at a key (Catmull-Rom): compare one-sided differences.
  const double h = 1e-4;
  const Eigen::Vector3d before = (path.at(2).eye - path.at(2 - h).eye) / h;
  const Eigen::Vector3d after = (path.at(2 + h).eye - path.at(2).eye) / h;
  EXPECT_LT((before - after).norm(), 1e-2 * before.norm());
}

TEST(CameraPath, ReplacesAndRemovesKeys) {
  CameraPath path;
  path.setKey(1.0, poseAt(0));
  path.setKey(1.0001, poseAt(1));  // within a millisecond: replaces
  ASSERT_EQ(path.keys().size(), 1u);
  EXPECT_LT((path.keys()[0].pose.eye - poseAt(1).eye).norm(), 1e-12);
  EXPECT_FALSE(path.removeKey(2.0));
  EXPECT_TRUE(path.removeKey(1.02));
  EXPECT_TRUE(path.empty());
}

}  // namespace
}  // namespace lumistage
