#include "core/live/vmc_sender.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <set>
#include <string>

#include "core/base/error.h"
#include "core/body/human_skeleton.h"
#include "tests/osc_receiver.h"

namespace lumistage {
namespace {

using testing::OscBundle;
using testing::OscMessage;
using testing::OscReceiver;

constexpr double kPi = std::numbers::pi;

TEST(OscTarget, ReadsHostAndPort) {
  const OscTarget v4 = parseOscTarget("127.0.0.1:39539");
  EXPECT_EQ(v4.host, "127.0.0.1");
  EXPECT_EQ(v4.port, 39539);
  const OscTarget named = parseOscTarget("studio-pc.local:9000");
  EXPECT_EQ(named.host, "studio-pc.local");
  EXPECT_EQ(named.port, 9000);
  const OscTarget v6 = parseOscTarget("[::1]:39540");
  EXPECT_EQ(v6.host, "::1");
  EXPECT_EQ(v6.port, 39540);
  EXPECT_EQ(v6.text(), "[::1]:39540");
  EXPECT_EQ(v4.text(), "127.0.0.1:39539");
}

TEST(OscTarget, RefusesWhatIsNotHostAndPortSayingWhy) {
  const std::map<std::string, std::string> why{
      {"127.0.0.1", "no port"},
      {":39539", "no host"},
      {"[]:39539", "no host"},
      {"localhost:", "1 to 65535"},
      {"localhost:0", "1 to 65535"},
      {"localhost:65536", "1 to 65535"},
      {"localhost:39539x", "1 to 65535"},
      {"localhost:-1", "1 to 65535"},
      {"::1:39539", "IPv6 address goes in brackets"},
  };
  for (const auto& [text, reason] : why) {
    try {
      parseOscTarget(text);
      ADD_FAILURE() << text << " was taken";
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(reason), std::string::npos) << text << ": " << message;
      EXPECT_NE(message.find("HOST:PORT"), std::string::npos) << message;
    }
  }
}

// Unity's quaternion of a rotation turns Unity's image of a vector as ours turns the vector:
// q_unity * S v == S (R v), for rotations about every axis and a mixed one.
TEST(UnityAxes, AConvertedRotationTurnsConvertedVectorsAsOursTurnsOurs) {
  const std::vector<Eigen::Matrix3d> rotations{
      Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitX()).toRotationMatrix(),
      Eigen::AngleAxisd(-1.1, Eigen::Vector3d::UnitY()).toRotationMatrix(),
      Eigen::AngleAxisd(2.5, Eigen::Vector3d::UnitZ()).toRotationMatrix(),
      eulerRotation(Eigen::Vector3d(0.3, -0.8, 1.9)),
  };
  const std::vector<Eigen::Vector3d> vectors{Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0),
                                             Eigen::Vector3d(0.2, -0.5, 0.9)};
  for (const Eigen::Matrix3d& r : rotations) {
    const Eigen::Quaterniond q = toUnityRotation(r);
    EXPECT_GE(q.w(), 0);
    EXPECT_NEAR(q.norm(), 1, 1e-12);
    for (const Eigen::Vector3d& v : vectors) {
      const Eigen::Vector3d theirs = q * toUnityPosition(v), ours = toUnityPosition(r * v);
      EXPECT_LT((theirs - ours).norm(), 1e-12) << theirs.transpose() << " / " << ours.transpose();
    }
  }
  // Up is Unity's +Y, the actor's forward its +Z, the actor's right its +X.
  EXPECT_EQ(toUnityPosition(Eigen::Vector3d(0, 0, 1)), Eigen::Vector3d(0, 1, 0));
  EXPECT_EQ(toUnityPosition(Eigen::Vector3d(0, 1, 0)), Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(toUnityPosition(Eigen::Vector3d(1, 0, 0)), Eigen::Vector3d(1, 0, 0));
}

// A pose of the generic human with the left elbow bent 90 degrees forward (about the vertical),
// the body turned 90 degrees to its left, moved and scaled, as the studio sends it.
PoseData bentElbowPose(const Skeleton& skeleton, double turn_rad) {
  PoseData pose;
  pose.root[0] = 0.4f;
  pose.root[1] = -0.3f;
  pose.root[2] = -0.1f;
  pose.scale = 1.1f;
  pose.angles.assign(size_t(3) * skeleton.jointCount(), 0.0f);
  pose.angles[2] = float(turn_rad);                   // the root's rotation vector, about z
  pose.angles[3 * kLeftElbow + 2] = float(-kPi / 2);  // the left forearm from -x to +y
  return pose;
}

const OscMessage* findBone(const OscBundle& bundle, const std::string& name) {
  for (const OscMessage& m : bundle)
    if (m.path == "/VMC/Ext/Bone/Pos" && m.text(0) == name) return &m;
  return nullptr;
}

Eigen::Vector3d positionOf(const OscMessage& m) {
  return {m.number(1), m.number(2), m.number(3)};
}
Eigen::Quaterniond rotationOf(const OscMessage& m) {
  return {m.number(7), m.number(4), m.number(5), m.number(6)};  // w, x, y, z
}

TEST(VmcSender, AReceiverGetsTheFramesPoseInUnitysAxes) {
  OscReceiver receiver;
  ASSERT_GT(receiver.port(), 0);
  const Skeleton skeleton = makeHumanSkeleton();
  VmcSender sender({"127.0.0.1", receiver.port()}, skeleton);
  const PoseData pose = bentElbowPose(skeleton, kPi / 2);
  ASSERT_TRUE(sender.send(pose, true));
  const std::vector<OscBundle> bundles = receiver.waitForBundles(1);
  ASSERT_EQ(bundles.size(), 1u);
  EXPECT_EQ(receiver.loose(), 0u);
  const OscBundle& bundle = bundles[0];

  // The root, then the 22 bones, then OK and the time.
  ASSERT_EQ(bundle.size(), 25u);
  EXPECT_EQ(bundle.front().path, "/VMC/Ext/Root/Pos");
  EXPECT_EQ(bundle.front().types, "sfffffff");
  EXPECT_EQ(bundle.front().text(0), "root");
  EXPECT_EQ(bundle.front().number(7), 1.0f);  // identity: the stage's origin is the root
  std::set<std::string> names;
  for (size_t m = 1; m < 23; ++m) {
    EXPECT_EQ(bundle[m].path, "/VMC/Ext/Bone/Pos");
    EXPECT_EQ(bundle[m].types, "sfffffff");
    names.insert(bundle[m].text(0));
  }
  const std::set<std::string> expected{
      "Hips",          "Spine",         "Chest",         "UpperChest",    "Neck",
      "Head",          "LeftShoulder",  "LeftUpperArm",  "LeftLowerArm",  "LeftHand",
      "RightShoulder", "RightUpperArm", "RightLowerArm", "RightHand",     "LeftUpperLeg",
      "LeftLowerLeg",  "LeftFoot",      "LeftToes",      "RightUpperLeg", "RightLowerLeg",
      "RightFoot",     "RightToes"};
  EXPECT_EQ(names, expected);
  EXPECT_EQ(bundle[23].path, "/VMC/Ext/OK");
  ASSERT_EQ(bundle[23].types, "iii");
  EXPECT_EQ(bundle[23].integer(0), 1);  // loaded
  EXPECT_EQ(bundle[23].integer(1), 3);  // calibrated: tracked
  EXPECT_EQ(bundle[24].path, "/VMC/Ext/T");
  EXPECT_GE(bundle[24].number(0), 0.0f);

  // The hips where the studio's pose puts the pelvis, scaled about the stage's origin: (x, z, y).
  const Eigen::Vector3d pelvis =
      pose.scale * (skeleton.joint(kPelvis).offset_m + Eigen::Vector3d(0.4, -0.3, -0.1));
  const OscMessage* hips = findBone(bundle, "Hips");
  ASSERT_TRUE(hips);
  EXPECT_LT((positionOf(*hips) - Eigen::Vector3d(pelvis.x(), pelvis.z(), pelvis.y())).norm(), 1e-5)
      << positionOf(*hips).transpose();
  // Turned 90 degrees to the actor's left (about our z, counter-clockwise from above): facing -x,
  // Unity's -X. Unity's forward (+Z) turned by the hips' quaternion is -X.
  const Eigen::Vector3d facing = rotationOf(*hips) * Eigen::Vector3d(0, 0, 1);
  EXPECT_LT((facing - Eigen::Vector3d(-1, 0, 0)).norm(), 1e-5) << facing.transpose();

  // The left elbow bent forward: the lower arm's local rotation is +90 degrees about Unity's Y
  // (0, sin 45, 0, cos 45), which turns the forearm's rest direction (the left, -X) to forward
  // (+Z).
  const OscMessage* elbow = findBone(bundle, "LeftLowerArm");
  ASSERT_TRUE(elbow);
  const double h = std::sqrt(0.5);
  EXPECT_LT((rotationOf(*elbow).coeffs() - Eigen::Vector4d(0, h, 0, h)).norm(), 1e-5)
      << rotationOf(*elbow).coeffs().transpose();
  const Eigen::Vector3d forearm = rotationOf(*elbow) * Eigen::Vector3d(-1, 0, 0);
  EXPECT_LT((forearm - Eigen::Vector3d(0, 0, 1)).norm(), 1e-5) << forearm.transpose();
  // Its place: the upper arm's length along the left (-X), scaled.
  EXPECT_LT((positionOf(*elbow) - Eigen::Vector3d(-0.28 * 1.1, 0, 0)).norm(), 1e-5)
      << positionOf(*elbow).transpose();
  // Bones not bent stay at their rest rotation (identity), the right elbow among them.
  for (const char* name : {"RightLowerArm", "LeftUpperArm", "Spine", "LeftLowerLeg"}) {
    const OscMessage* bone = findBone(bundle, name);
    ASSERT_TRUE(bone) << name;
    EXPECT_NEAR(rotationOf(*bone).w(), 1, 1e-6) << name;
  }
  // The left hand hangs on at the end of the bent forearm: its local place is along the forearm's
  // rest direction (its parent's frame), not turned itself.
  const OscMessage* hand = findBone(bundle, "LeftHand");
  ASSERT_TRUE(hand);
  EXPECT_LT((positionOf(*hand) - Eigen::Vector3d(-0.25 * 1.1, 0, 0)).norm(), 1e-5);
  EXPECT_EQ(sender.bundlesSent(), 1);
}

TEST(VmcSender, SaysUncalibratedWhileNobodyIsTrackedAndSendsEveryFrame) {
  OscReceiver receiver;
  const Skeleton skeleton = makeHumanSkeleton();
  VmcSender sender({"127.0.0.1", receiver.port()}, skeleton);
  for (int frame = 0; frame < 5; ++frame)
    EXPECT_TRUE(sender.send(bentElbowPose(skeleton, 0.1 * frame), frame >= 2));
  const std::vector<OscBundle> bundles = receiver.waitForBundles(5);
  ASSERT_EQ(bundles.size(), 5u);
  for (size_t b = 0; b < bundles.size(); ++b) {
    ASSERT_EQ(bundles[b].size(), 25u);
    EXPECT_EQ(bundles[b][23].integer(1), b >= 2 ? 3 : 0) << b;
    // Each frame's own pose: the hips turned 0.1 rad more each frame (about Unity's Y, the other
    // way round).
    const Eigen::Quaterniond hips = rotationOf(*findBone(bundles[b], "Hips"));
    EXPECT_NEAR(2 * std::atan2(-hips.y(), hips.w()), 0.1 * double(b), 1e-5) << b;
  }
  EXPECT_EQ(sender.bundlesSent(), 5);
  EXPECT_EQ(sender.bundlesLost(), 0);
}

// UDP: a receiver that is not there (the port closed) costs nothing and stops nothing.
TEST(VmcSender, NoReceiverThereIsNoError) {
  int port = 0;
  {
    OscReceiver gone;
    port = gone.port();
  }
  const Skeleton skeleton = makeHumanSkeleton();
  VmcSender sender({"127.0.0.1", port}, skeleton);
  for (int frame = 0; frame < 3; ++frame) sender.send(bentElbowPose(skeleton, 0), true);
  EXPECT_EQ(sender.bundlesSent() + sender.bundlesLost(), 3);
}

TEST(VmcSender, RefusesASkeletonWithoutAPelvis) {
  Skeleton other(
      {{"root", -1, Eigen::Vector3d(0, 0, 1), {}}, {"tip", 0, Eigen::Vector3d(0, 0, 1), {}}});
  EXPECT_THROW(VmcSender({"127.0.0.1", 39539}, other), Error);
}

}  // namespace
}  // namespace lumistage
