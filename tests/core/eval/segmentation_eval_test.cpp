// The segmentation as the nodes run it, against the virtual studio's exact silhouettes.
#include "core/eval/segmentation_eval.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/capture/session_writer.h"
#include "core/geometry/ring_rig.h"
#include "core/imaging/keyer.h"
#include "core/sim/virtual_studio.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

// The reference studio's actor, clothes and green spill, filmed by 4 cameras of 640x480 in RGB.
fs::path writeSession(int frames) {
  const fs::path folder = testing::testFolder("segmentation") / "session";
  StudioConfig config =
      loadStudioConfig(std::string(LUMISTAGE_TEST_RESOURCE_DIR) + "/studio/reference.yaml");
  RingRigSpec spec;
  spec.cameras = 4;
  spec.width = 640;
  spec.height = 480;
  config.rig = makeRingRig(spec);
  config.actor.target_vertices = 4000;
  VirtualStudio studio(config, frames);
  std::vector<std::string> joints;
  for (const Joint& joint : studio.actor().skeleton.joints()) joints.push_back(joint.name);
  SessionWriter writer(folder, config.rig, PixelFormat::kRgb8, config.fps, "test", joints);
  StudioFrame frame;
  std::vector<Image> images(spec.cameras);
  std::vector<ImageView> views(spec.cameras);
  for (int f = 0; f < frames; ++f) {
    studio.renderFrame(f * 10, frame);
    for (int c = 0; c < spec.cameras; ++c) {
      rgbaToImage(frame.images[c].data(), spec.width, spec.height, PixelFormat::kRgb8, images[c]);
      views[c] = images[c].view();
    }
    FrameTruth truth{frame.joints, &frame.surface, &frame.masks};
    writer.writeFrame(f, f * 33'333'333, views, &truth);
  }
  return folder;
}

TEST(Segmentation, KeyerLearntWithTheActorInViewFindsTheSpilledEdges) {
  const SessionReader session(writeSession(3));
  const SegmentationScore score = evaluateSegmentation(session, {1, 2});
  EXPECT_EQ(score.frames, 2);
  EXPECT_GT(score.threshold, 12);
  EXPECT_GE(score.dimmest_screen, GreenScreenKeyer::kDimScreenExcess);
  // The actor's edges take the screen's green light. A threshold at half the screen's darkest
  // green excess missed 0.68% of the actor's pixels here; at three quarters, 0.14%.
  EXPECT_LT(score.missed_pct, 0.3);
  EXPECT_LT(score.extra_pct, 0.05);
  fs::remove_all(session.folder().parent_path());
}

TEST(Segmentation, AnUnreadableTruthMaskIsNamed) {
  const SessionReader session(writeSession(1));
  const fs::path mask = session.truthMaskPath(2, 0);
  std::ofstream(mask, std::ios::trunc) << "not a png";
  EXPECT_NE(testing::errorOf([&] { evaluateSegmentation(session, {0}); }).find(mask.string()),
            std::string::npos);
  fs::remove_all(session.folder().parent_path());
}

}  // namespace
}  // namespace lumistage
