// The initialisation's shortcuts are exact: a hull sample's nearest capsule found through the
// capsules' bounding spheres is the nearest of all of them, and a hypothesis's score is the fit's
// cost (or, given up early, more than the bound it passed).
#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "core/base/resource_path.h"
#include "core/body/human_model.h"
#include "core/sim/studio_config.h"
#include "core/tracking/pose_tracker_impl.h"

namespace lumistage {
namespace {

using tracker_detail::segmentDistance;

struct TrackerModel {
  PoseTracker::Impl impl;
  std::mt19937 random{7};

  TrackerModel()
      : impl(loadStudioConfig(resourcePath("studio/reference.yaml").string()).rig,
             makeHumanModel({}), PoseTrackerOptions{}) {}

  // A walking-like pose: every joint turned a little at random.
  Pose randomPose() {
    std::normal_distribution<double> angle(0.0, 0.25);
    Pose p = Pose::rest(impl.skeleton.jointCount());
    for (Eigen::Vector3d& a : p.angles_rad)
      a = Eigen::Vector3d(angle(random), angle(random), angle(random));
    p.root_translation_m = Eigen::Vector3d(0.1, -0.2, 0.95);
    return p;
  }

  void place(const Pose& p) {
    impl.skeleton.forwardKinematics(p, impl.global);
    impl.capsuleEnds(impl.cap_a, impl.cap_b);
    impl.capsuleSpheres();
  }

  // Points about the body: near its joints, scattered by up to 30 cm.
  std::vector<Eigen::Vector3d> pointsAbout(int count) {
    std::uniform_int_distribution<int> joint(0, int(impl.global.size()) - 1);
    std::normal_distribution<double> off(0.0, 0.15);
    std::vector<Eigen::Vector3d> points;
    for (int i = 0; i < count; ++i)
      points.push_back(impl.global[joint(random)].translation() +
                       Eigen::Vector3d(off(random), off(random), off(random)));
    return points;
  }
};

TEST(CapsuleDistance, TheBoundingSpheresMissNoCapsuleNearTheNearest) {
  TrackerModel m;
  PoseTracker::Impl& impl = m.impl;
  const size_t n = impl.capsules.size();
  Eigen::Vector3d point;
  int skipped = 0, measured = 0;
  for (int trial = 0; trial < 5; ++trial) {
    m.place(m.randomPose());
    int hint = 0;
    for (const Eigen::Vector3d& x : m.pointsAbout(400)) {
      for (double margin : {0.0, 0.1}) {
        const double nearest = impl.hullDistances(x, hint, margin);
        double truth = std::numeric_limits<double>::infinity();
        for (size_t c = 0; c < n; ++c)
          truth = std::min(truth, segmentDistance(x, impl.cap_a[c], impl.cap_b[c], point) -
                                      impl.capsules[c].radius_m);
        ASSERT_EQ(nearest, truth);
        // Every capsule within the margin of the nearest measured, exactly.
        for (size_t c = 0; c < n; ++c) {
          const double d =
              segmentDistance(x, impl.cap_a[c], impl.cap_b[c], point) - impl.capsules[c].radius_m;
          if (d <= truth + margin) {
            ASSERT_EQ(impl.capsule_distance[c], d) << "capsule " << c;
            ++measured;
          } else if (std::isinf(impl.capsule_distance[c])) {
            ++skipped;
          }
        }
      }
    }
  }
  // And it saves work: most capsules are never measured.
  EXPECT_GT(skipped, measured);
}

TEST(CapsuleDistance, AHypothesissScoreIsTheFitsCostOrMoreThanItsBound) {
  TrackerModel m;
  PoseTracker::Impl& impl = m.impl;
  m.place(m.randomPose());
  impl.hull = m.pointsAbout(300);  // a hull near the first pose: the others are scored against it
  for (int trial = 0; trial < 6; ++trial) {
    const Pose p = m.randomPose();
    impl.candidates_valid = false;
    const double cost = impl.evaluate(p, false, impl.H, impl.g);
    ASSERT_GT(cost, 0);
    EXPECT_NEAR(impl.score(p, std::numeric_limits<double>::infinity()), cost, 1e-9 * cost);
    // Given up before the end: more than the bound, no more than the whole.
    const double early = impl.score(p, 0.2 * cost);
    EXPECT_GT(early, 0.2 * cost);
    EXPECT_LE(early, cost * (1 + 1e-9));
  }
}

}  // namespace
}  // namespace lumistage
