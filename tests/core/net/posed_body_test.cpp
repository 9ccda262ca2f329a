#include "core/net/posed_body.h"

#include <gtest/gtest.h>

#include "core/body/human_skeleton.h"
#include "core/body/motion_library.h"

namespace lumistage {
namespace {

// Mean distance between two sets of joints, metres.
double meanJointError(const std::vector<Eigen::Vector3d>& a,
                      const std::vector<Eigen::Vector3d>& b) {
  double sum = 0;
  for (size_t j = 0; j < a.size(); ++j) sum += (a[j] - b[j]).norm();
  return sum / double(a.size());
}

// The joints of the generic skeleton posed by a message, as the nodes pose the generic human.
std::vector<Eigen::Vector3d> posedJoints(const Skeleton& generic, const PoseData& message) {
  std::vector<Eigen::Vector3d> joints;
  generic.jointPositions(poseFromMessage(message, generic.jointCount()), joints);
  for (Eigen::Vector3d& j : joints) j *= message.scale;
  return joints;
}

// An actor taller than the generic human, with longer legs and shorter arms (the virtual studio's
// reference actor), tracked in the middle of a crouch.
struct CrouchingActor {
  Skeleton generic = makeHumanSkeleton();
  Skeleton calibrated =
      makeHumanSkeleton({.height_m = 1.82, .arm_length_scale = 0.97, .leg_length_scale = 1.04});
  Pose tracked;
  std::vector<Eigen::Vector3d> joints;
  CrouchingActor() {
    const MotionClip clip = makeBuiltinClip("crouch", calibrated, 30, 3);
    tracked = clip.sample(1.0);
    tracked.root_translation_m += Eigen::Vector3d(0.4, -0.3, 0);
    calibrated.jointPositions(tracked, joints);
  }
};

TEST(PoseMessage, PutsTheGenericJointsOnTheTrackedOnesWhateverTheActorsProportions) {
  const CrouchingActor actor;
  const PoseData message =
      poseMessageFor(actor.generic, actor.calibrated, actor.tracked, actor.joints);
  const double error = meanJointError(posedJoints(actor.generic, message), actor.joints);

  // The tracked angles on the generic skeleton, scaled by the pelvis heights (the message before
  // 2026-12-02): the joints land centimetres off.
  PoseData angles;
  angles.scale =
      float(actor.calibrated.restPositions()[0].z() / actor.generic.restPositions()[0].z());
  const Eigen::Vector3d root =
      (actor.calibrated.restPositions()[0] + actor.tracked.root_translation_m) / angles.scale -
      actor.generic.restPositions()[0];
  for (int k = 0; k < 3; ++k) angles.root[k] = float(root[k]);
  for (const Eigen::Vector3d& a : actor.tracked.angles_rad)
    angles.angles.insert(angles.angles.end(), {float(a.x()), float(a.y()), float(a.z())});
  const double angles_error = meanJointError(posedJoints(actor.generic, angles), actor.joints);

  EXPECT_LT(error, 0.012) << "mean joint error " << error * 1e3 << " mm";
  EXPECT_LT(error, 0.7 * angles_error)
      << error * 1e3 << " mm against " << angles_error * 1e3 << " mm";
  // One scale for the actor, from the skeletons alone: the body does not swell and shrink from
  // frame to frame with the pose.
  const Pose standing = Pose::rest(actor.calibrated.jointCount());
  std::vector<Eigen::Vector3d> standing_joints;
  actor.calibrated.jointPositions(standing, standing_joints);
  EXPECT_EQ(poseMessageFor(actor.generic, actor.calibrated, standing, standing_joints).scale,
            message.scale);
  EXPECT_GT(message.scale, 1.82 / 1.75);
  EXPECT_LT(message.scale, 1.82 / 1.75 * 1.04);
}

TEST(PoseMessage, AnActorOfTheGenericProportionsGetsTheTrackedJoints) {
  const Skeleton generic = makeHumanSkeleton();
  const Skeleton calibrated = makeHumanSkeleton({.height_m = 1.66});
  const MotionClip clip = makeBuiltinClip("arm_wave", calibrated, 30, 3);
  std::vector<Eigen::Vector3d> joints;
  for (double t : {0.5, 1.0, 1.5}) {
    const Pose tracked = clip.sample(t);
    calibrated.jointPositions(tracked, joints);
    const PoseData message = poseMessageFor(generic, calibrated, tracked, joints);
    EXPECT_NEAR(message.scale, 1.66 / 1.75, 1e-4);
    EXPECT_LT(meanJointError(posedJoints(generic, message), joints), 0.002) << "t = " << t;
  }
}

}  // namespace
}  // namespace lumistage
