#include "core/sim/stage_draw.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <numbers>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/body/human_skeleton.h"
#include "core/body/motion_library.h"
#include "core/geometry/rig_file.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

const fs::path kMotions = testing::realData() / "motions";

TEST(StageDraw, TheSameSeedDrawsTheSameStageAndOthersDiffer) {
  const std::string a = formatStudioConfig(drawStage(7), "rig.yaml");
  EXPECT_EQ(a, formatStudioConfig(drawStage(7), "rig.yaml"));
  EXPECT_EQ(formatRig(drawStage(7).rig), formatRig(drawStage(7).rig));
  EXPECT_NE(a, formatStudioConfig(drawStage(8), "rig.yaml"));
  EXPECT_NE(formatRig(drawStage(7).rig), formatRig(drawStage(8).rig));
}

// Every drawn stage is within the corpus's ranges, and every camera sees the whole column the
// actor may move in (1 m about the centre, 2.5 m tall), inside its image with its lens.
TEST(StageDraw, StagesStayInTheirRangesAndEveryCameraSeesTheActorsColumn) {
  StageDrawOptions options;
  int twelve_or_more = 0, bayer = 0, clothed = 0, starts_in_clip = 0;
  double shortest = 10, tallest = 0;
  for (uint32_t seed = 1; seed <= 30; ++seed) {
    SCOPED_TRACE(seed);
    const StudioConfig c = drawStage(seed, options);
    const Rig& rig = c.rig;
    ASSERT_GE(rig.cameraCount(), options.min_cameras);
    ASSERT_LE(rig.cameraCount(), options.max_cameras);
    for (const RigNode& node : rig.nodes()) {
      EXPECT_GE(node.cameras.size(), 1u);
      EXPECT_LE(node.cameras.size(), 4u);
    }
    ASSERT_TRUE(rig.stage().has_value());
    for (const Camera& camera : rig.cameras()) {
      EXPECT_GE(camera.centre().z(), 0.5);
      EXPECT_LE(camera.centre().z(), 3.0);
      const double r = camera.centre().head<2>().norm();
      EXPECT_GT(r, 2.7);
      EXPECT_LT(r, 5.1);
      EXPECT_LE(std::abs(camera.intrinsics().cx - 0.5 * (camera.width() - 1)), 14.0);
      for (int a = 0; a < 16; ++a)
        for (double z : {0.0, 1.25, 2.5}) {
          const double angle = 2 * std::numbers::pi * a / 16;
          const Eigen::Vector3d p(std::cos(angle), std::sin(angle), z);
          const std::optional<Eigen::Vector2d> px = camera.project(p);
          ASSERT_TRUE(px.has_value()) << camera.name();
          EXPECT_GE(px->x(), 0) << camera.name();
          EXPECT_LT(px->x(), camera.width()) << camera.name();
          EXPECT_GE(px->y(), 0) << camera.name();
          EXPECT_LT(px->y(), camera.height()) << camera.name();
        }
    }
    const double h = c.actor.shape.height_m;
    EXPECT_GE(h, 1.50);
    EXPECT_LE(h, 2.05);
    shortest = std::min(shortest, h);
    tallest = std::max(tallest, h);
    EXPECT_TRUE(c.placement.centre);
    EXPECT_LE(c.placement.offset_m.norm(), 0.6);
    starts_in_clip += c.placement.start_s < 0.5;
    twelve_or_more += rig.cameraCount() >= 12;
    bayer += c.pixel_format != PixelFormat::kRgb8;
    clothed += c.actor.clothing;
  }
  // Spread, not stuck at one end.
  EXPECT_LT(shortest, 1.62);
  EXPECT_GT(tallest, 1.93);
  EXPECT_GT(twelve_or_more, 0);
  EXPECT_GT(bayer, 10);
  EXPECT_LT(bayer, 30);
  EXPECT_GT(clothed, 15);
  EXPECT_LT(starts_in_clip, 15);  // mostly not the T-pose the built-in clips open with
}

TEST(StageDraw, OptionsLimitOnlyTheirPart) {
  StageDrawOptions small;
  small.min_cameras = 4;
  small.max_cameras = 6;
  small.clips = {"crouch"};
  small.any_start = false;
  for (uint32_t seed = 1000; seed < 1010; ++seed) {
    const StudioConfig c = drawStage(seed, small);
    EXPECT_GE(c.rig.cameraCount(), 4);
    EXPECT_LE(c.rig.cameraCount(), 6);
    EXPECT_EQ(c.clip, "crouch");
    EXPECT_EQ(c.placement.start_s, 0);
    // The actor and the look are the seed's whatever the rig and motion options.
    const StudioConfig d = drawStage(seed);
    EXPECT_EQ(c.actor.shape.height_m, d.actor.shape.height_m);
    EXPECT_EQ(c.look.screen_green, d.look.screen_green);
  }
  StageDrawOptions wrong;
  wrong.min_cameras = 9;
  wrong.max_cameras = 8;
  EXPECT_THROW(drawStage(1, wrong), Error);
}

TEST(StageDraw, RealMotionFilesAreDrawnAndPlayWithinTheirLength) {
  if (!fs::exists(kMotions / "cmu-01_03.bvh")) GTEST_SKIP() << kMotions << " is not here";
  StageDrawOptions options;
  options.clips = {"walk"};
  options.bvh_files = {kMotions / "cmu-01_03.bvh"};
  int real = 0;
  for (uint32_t seed = 1; seed <= 12; ++seed) {
    const StudioConfig c = drawStage(seed, options);
    if (c.bvh_file.empty()) continue;
    ++real;
    EXPECT_EQ(c.bvh_file.filename(), "cmu-01_03.bvh");
    EXPECT_GE(c.placement.start_s, 0);
  }
  EXPECT_GT(real, 2);
  EXPECT_LT(real, 12);
}

// What synth --seed writes beside the session is read back as the same stage.
TEST(StageDraw, TheDrawnConfigReadsBackAsTheSameStage) {
  const fs::path folder =
      fs::temp_directory_path() / ("lumistage_stage_draw_" + std::to_string(::getpid()));
  fs::create_directories(folder);
  for (uint32_t seed : {3u, 1004u}) {
    const StudioConfig drawn = drawStage(seed);
    saveRig(drawn.rig, folder / "rig.yaml");
    writeFileAtomically(folder / "studio.yaml", formatStudioConfig(drawn, "rig.yaml"));
    const StudioConfig read = loadStudioConfig(folder / "studio.yaml");
    EXPECT_EQ(read.rig, drawn.rig);
    EXPECT_EQ(read.clip, drawn.clip);
    EXPECT_EQ(read.actor.clothing, drawn.actor.clothing);
    EXPECT_EQ(read.actor.target_vertices, drawn.actor.target_vertices);
    EXPECT_DOUBLE_EQ(read.actor.shape.height_m, drawn.actor.shape.height_m);
    EXPECT_DOUBLE_EQ(read.actor.shape.belly_scale, drawn.actor.shape.belly_scale);
    EXPECT_DOUBLE_EQ(read.placement.start_s, drawn.placement.start_s);
    EXPECT_DOUBLE_EQ(read.placement.heading_deg, drawn.placement.heading_deg);
    EXPECT_EQ(read.placement.offset_m, drawn.placement.offset_m);
    EXPECT_EQ(read.placement.centre, drawn.placement.centre);
    EXPECT_EQ(read.pixel_format, drawn.pixel_format);
    EXPECT_EQ(read.seed, seed);
    EXPECT_NEAR(read.look.noise_sigma, drawn.look.noise_sigma, 1e-7);
    EXPECT_EQ(read.look.screen_green, drawn.look.screen_green);
  }
  fs::remove_all(folder);
}

TEST(MotionPlacement, TurnsAndMovesTheWholeBodyAndCentresTheFilmedFrames) {
  const Skeleton skeleton = makeHumanSkeleton();
  const MotionClip walk = makeBuiltinClip("walk", skeleton, 30, 4);
  MotionClip placed = walk;
  MotionPlacement placement;
  placement.start_s = 1.0;
  placement.heading_deg = 90;
  placement.offset_m = {0.3, -0.2};
  placeMotion(placed, skeleton, placement, 60, 30);
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  std::vector<Eigen::Vector3d> before, after;
  for (double t : {0.0, 1.3, 2.9}) {
    skeleton.jointPositions(walk.sample(t), before);
    skeleton.jointPositions(placed.sample(t), after);
    for (size_t j = 0; j < before.size(); ++j) {
      const Eigen::Vector3d expected = turn * before[j] + Eigen::Vector3d(0.3, -0.2, 0);
      EXPECT_LT((after[j] - expected).norm(), 1e-9) << "joint " << j << " at " << t << " s";
    }
  }
  // Centred: the filmed frames' mean root lands on the offset.
  MotionClip centred = walk;
  placement.centre = true;
  placeMotion(centred, skeleton, placement, 60, 30);
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (int f = 0; f < 60; ++f) {
    skeleton.jointPositions(centred.sample(1.0 + f / 30.0), after);
    mean += after[0].head<2>() / 60;
  }
  EXPECT_LT((mean - placement.offset_m).norm(), 1e-9);
  placement.start_s = 10;
  EXPECT_THROW(placeMotion(centred, skeleton, placement, 60, 30), Error);
}

}  // namespace
}  // namespace lumistage
