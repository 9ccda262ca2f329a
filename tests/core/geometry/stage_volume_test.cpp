// The stage box the tracker carves: the rig file's, else the floor the cameras cover.
#include "core/geometry/stage_volume.h"

#include <gtest/gtest.h>

#include "core/geometry/ring_rig.h"

namespace lumistage {
namespace {

// How many cameras see the column at (x, y) whole, floor to kCoveredTop_m (pixel centres of the
// image's border count).
int camerasSeeingColumn(const Rig& rig, double x, double y) {
  int seen = 0;
  for (const Camera& c : rig.cameras()) {
    bool whole = true;
    for (double z : {0.0, kCoveredTop_m}) {
      const Eigen::Vector3d p(x, y, z);
      const std::optional<Eigen::Vector2d> px = c.project(p);
      whole = whole && (c.rotation() * p + c.translation()).z() > 0 && px && px->x() >= -0.5 &&
              px->y() >= -0.5 && px->x() <= c.width() - 0.5 && px->y() <= c.height() - 0.5;
    }
    seen += whole;
  }
  return seen;
}

// The box holds every column enough cameras see, and reaches no further than the rounding past
// the outermost ones (or the default box's floor, where that reaches further).
void expectBoundsTheCoveredFloor(const Rig& rig, const StageBox& box) {
  const int need = minViewsForStage(rig.cameraCount());
  Eigen::Vector2d lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
  for (double y = -6; y <= 6; y += 0.04) {
    for (double x = -6; x <= 6; x += 0.04) {
      if (camerasSeeingColumn(rig, x, y) < need) continue;
      EXPECT_TRUE(box.contains({x, y, 1.0})) << x << ", " << y;
      lo = lo.cwiseMin(Eigen::Vector2d(x, y));
      hi = hi.cwiseMax(Eigen::Vector2d(x, y));
    }
  }
  ASSERT_LT(lo.x(), hi.x());
  const StageBox least;
  for (int k = 0; k < 2; ++k) {
    EXPECT_GT(std::min(lo[k], least.lower[k]) - box.lower[k], -0.2) << k;
    EXPECT_LT(std::max(hi[k], least.upper[k]) - box.upper[k], 0.2) << k;
  }
  EXPECT_EQ(box.lower.z(), 0.0);
  EXPECT_EQ(box.upper.z(), kCoveredTop_m);
}

TEST(StageVolume, TheReferenceRigCoversItsThreeMetreStageAndALittleMore) {
  const Rig rig = makeRingRig({});
  EXPECT_EQ(minViewsForStage(12), 9);
  const StageChoice choice = chooseStage(rig);
  EXPECT_FALSE(choice.guessed);
  expectBoundsTheCoveredFloor(rig, choice.box);
  EXPECT_TRUE(choice.box.contains({-1.5, -1.5, 0}));
  EXPECT_TRUE(choice.box.contains({1.5, 1.5, 2.4}));
  EXPECT_LT(choice.box.size().x(), 4.5);
  EXPECT_NE(choice.how.find("9 of the 12 cameras see whole"), std::string::npos) << choice.how;
}

// A wider ring on wider lenses: the stage grows with it (the tracker used to search 3 x 3 m
// whatever the rig).
TEST(StageVolume, AWiderRingCoversAWiderStage) {
  RingRigSpec spec;
  spec.radius_m = 4.2;
  spec.vertical_fov_deg = 48;
  const Rig rig = makeRingRig(spec);
  const StageBox box = stageVolume(rig);
  expectBoundsTheCoveredFloor(rig, box);
  EXPECT_TRUE(box.contains({-2.1, -2.1, 0}));
  EXPECT_TRUE(box.contains({2.1, 2.1, 2.4}));
}

// Lenses just wide enough for 9 cameras to share a spot of the floor: the box is still the 3 x 3
// m the tracker always searched, not that spot (it was 0.4 x 0.4 m).
TEST(StageVolume, CamerasThatBarelyAgreeKeepTheDefaultFloor) {
  RingRigSpec spec;
  spec.vertical_fov_deg = 42.6;
  const StageChoice choice = chooseStage(makeRingRig(spec));
  ASSERT_FALSE(choice.guessed);
  EXPECT_TRUE(choice.box.contains({-1.5, -1.5, 0}));
  EXPECT_TRUE(choice.box.contains({1.5, 1.5, 2.4}));
}

// A wide ring on wide lenses covers more floor than its tables should hold: the box stops at 5 m a
// side (14 x 14 m before, which the tracker refused), and a rig in centimetres gives a box, not
// a search of a 400 m floor at 5 cm.
TEST(StageVolume, TheCoveredFloorIsAtMostFiveMetresASide) {
  RingRigSpec spec;
  spec.radius_m = 9;
  spec.vertical_fov_deg = 70;
  const StageBox wide = stageVolume(makeRingRig(spec));
  EXPECT_NEAR(wide.size().x(), kMaxCoveredSide_m, 1e-9);
  EXPECT_NEAR(wide.size().y(), kMaxCoveredSide_m, 1e-9);
  EXPECT_TRUE(wide.contains({0, 0, 1}));
  spec = RingRigSpec{};
  spec.radius_m = 360;
  spec.heights_m = {230, 90};
  spec.target_m = {0, 0, 100};
  const StageBox centimetres = stageVolume(makeRingRig(spec));
  EXPECT_LE(centimetres.size().x(), kMaxCoveredSide_m + 1e-9);
  EXPECT_LE(centimetres.size().y(), kMaxCoveredSide_m + 1e-9);
}

TEST(StageVolume, TheRigFilesStageWins) {
  Rig rig = makeRingRig({});
  const StageBox given{{-1, -2, 0}, {3, 2, 2.6}};
  rig.setStage(given);
  const StageChoice choice = chooseStage(rig);
  EXPECT_TRUE(choice.box == given);
  EXPECT_NE(choice.how.find("from the rig file"), std::string::npos) << choice.how;
}

// Cameras that all look away from the stage share no floor: the default box, said to be a guess.
TEST(StageVolume, CamerasThatShareNoFloorGiveAGuessThatSaysSo) {
  RingRigSpec spec;
  spec.target_m = {0, 0, 40};  // every camera looks at the sky
  const StageChoice choice = chooseStage(makeRingRig(spec));
  EXPECT_TRUE(choice.guessed);
  EXPECT_TRUE(choice.box == StageBox{});
  EXPECT_NE(choice.how.find("give the rig file a `stage`"), std::string::npos) << choice.how;
}

TEST(StageVolume, ABoxTheTrackerCannotUseIsRefused) {
  Rig rig = makeRingRig({});
  EXPECT_THROW(rig.setStage(StageBox{{1, -1, 0}, {-1, 1, 2}}), std::invalid_argument);
  EXPECT_THROW(rig.setStage(StageBox{{-1, -1, 0}, {1, 1, NAN}}), std::invalid_argument);
  EXPECT_THROW(rig.setStage(StageBox{{-1, -1, 1}, {1, 1, 2}}), std::invalid_argument);
  EXPECT_THROW(rig.setStage(StageBox{{-1, -1, 0}, {1, 1, 0.9}}), std::invalid_argument);
  EXPECT_THROW(rig.setStage(StageBox{{-1, -1, -2}, {1, 1, 2}}), std::invalid_argument);
  EXPECT_THROW(rig.setStage(StageBox{{-150, -150, 0}, {150, 150, 240}}), std::invalid_argument);
  EXPECT_FALSE(rig.stage());
  rig.setStage(StageBox{{-1, -1, -0.1}, {1, 1, 2}});
  EXPECT_TRUE(rig.stage());
}

}  // namespace
}  // namespace lumistage
