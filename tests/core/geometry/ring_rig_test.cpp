#include "core/geometry/ring_rig.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/geometry/rig_file.h"

namespace lumistage {
namespace {

TEST(RingRig, ShippedReferenceRigIsTheDefaultRing) {
  // resources/rigs/reference.yaml is written by `lumistage rig ring`; it must not drift.
  const Rig shipped = loadRig(std::string(LUMISTAGE_TEST_RESOURCE_DIR) + "/rigs/reference.yaml");
  EXPECT_TRUE(shipped == makeRingRig({}));
  EXPECT_EQ(shipped.cameraCount(), 12);
  EXPECT_EQ(shipped.nodeCount(), 4);
}

TEST(RingRig, EveryCameraSeesTheWholeActingVolume) {
  // Every point up to 2 m high within 1.3 m of the stage centre is on every camera's image.
  const Rig rig = makeRingRig({});
  int seen = 0, total = 0;
  for (const Camera& camera : rig.cameras()) {
    for (double r = 0; r <= 1.3; r += 0.1) {
      for (double a = 0; a < 2 * std::numbers::pi; a += std::numbers::pi / 32) {
        for (double z = 0; z <= 2.0; z += 0.25) {
          const std::optional<Eigen::Vector2d> pixel =
              camera.project(Eigen::Vector3d(r * std::cos(a), r * std::sin(a), z));
          ++total;
          seen += pixel && camera.inImage(*pixel);
        }
      }
    }
  }
  EXPECT_EQ(seen, total);
  // Just outside, at the stage's corners, a point is no longer seen by all.
  int corner_seen = 0;
  for (const Camera& camera : rig.cameras()) {
    const std::optional<Eigen::Vector2d> pixel = camera.project(Eigen::Vector3d(1.5, 1.5, 2.0));
    corner_seen += pixel && camera.inImage(*pixel);
  }
  EXPECT_LT(corner_seen, 12);
}

TEST(RingRig, HeightsAlternateAndNodesAreDealtInTurn) {
  const Rig rig = makeRingRig({});
  for (int i = 0; i < rig.cameraCount(); ++i) {
    EXPECT_NEAR(rig.camera(i).centre().z(), i % 2 ? 0.9 : 2.3, 1e-12);
    EXPECT_NEAR(rig.camera(i).centre().head<2>().norm(), 3.6, 1e-12);
    EXPECT_EQ(rig.nodeOfCamera(i), i % 4);
  }
  // Level horizon: every camera's x axis is horizontal.
  for (const Camera& c : rig.cameras()) EXPECT_NEAR(c.rotation()(0, 2), 0.0, 1e-12);
}

TEST(RingRig, AFrameSetHoldsEachCamerasPixels) {
  const Rig rig = makeRingRig({});
  EXPECT_EQ(rig.pixelsPerSet(), int64_t(12) * 1024 * 768);
  EXPECT_EQ(rig.pixelsPerSet(rig.nodes()[0].cameras), int64_t(3) * 1024 * 768);
  EXPECT_EQ(rig.pixelsPerSet(std::vector<int>{}), 0);
}

}  // namespace
}  // namespace lumistage
