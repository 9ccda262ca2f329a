// The segmentation as the nodes run it, against the virtual studio's exact silhouettes.
#include "core/eval/segmentation_eval.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/imaging/keyer.h"
#include "core/sim/virtual_studio.h"
#include "tests/core/sim/reference_studio.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

// The reference studio's actor, clothes and green spill, filmed by 4 cameras of 640x480 in RGB,
// every tenth frame of the clip.
fs::path writeSession(int frames) {
  const fs::path folder = testing::testFolder("segmentation") / "session";
  VirtualStudio studio(testing::referenceStudioOnRing(4000, 4, 640, 480), frames * 10);
  const std::unique_ptr<SessionWriter> writer = openStudioSession(studio, folder);
  StudioFrame frame;
  std::vector<Image> images;
  for (int f = 0; f < frames; ++f) {
    studio.renderFrame(f * 10, frame);
    writeStudioFrame(studio, frame, f, *writer, images);
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
