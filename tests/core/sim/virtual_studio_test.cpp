#include "core/sim/virtual_studio.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "core/base/error.h"
#include "tests/core/sim/reference_studio.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

const fs::path kReference = fs::path(LUMISTAGE_TEST_RESOURCE_DIR) / "studio" / "reference.yaml";

TEST(StudioConfig, ReferenceStudioLoads) {
  const StudioConfig config = loadStudioConfig(kReference);
  EXPECT_EQ(config.rig.cameraCount(), 12);
  EXPECT_EQ(config.clip, "walk");
  EXPECT_DOUBLE_EQ(config.actor.shape.height_m, 1.82);
  EXPECT_TRUE(config.actor.clothing);
  EXPECT_NEAR(config.look.noise_sigma * 255, 2.0, 1e-6);
}

TEST(StudioConfig, MistakesAreNamed) {
  const fs::path folder =
      fs::temp_directory_path() / ("lumistage_studio_" + std::to_string(::getpid()));
  fs::create_directories(folder);
  auto errorOf = [&](const std::string& text) {
    std::ofstream(folder / "studio.yaml") << text;
    try {
      loadStudioConfig(folder / "studio.yaml");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string rig =
      "rig: " + (kReference.parent_path().parent_path() / "rigs" / "reference.yaml").string() +
      "\n";
  const std::string head = "format: lumistage-studio\nversion: 1\n" + rig;
  EXPECT_NE(errorOf(head + "motion:\n  clip: moonwalk\n")
                .find("studio.yaml:5: motion.clip: unknown clip 'moonwalk'; expected one of: walk"),
            std::string::npos);
  EXPECT_NE(errorOf(head + "look:\n  pixel_format: yuv\n")
                .find("look.pixel_format: expected one of mono8, bayer_rggb8, bayer_grbg8, "
                      "bayer_gbrg8, bayer_bggr8, rgb8"),
            std::string::npos);
  EXPECT_NE(
      errorOf(head + "actor:\n  height_m: -2\n").find("actor.height_m: expected a positive number"),
      std::string::npos);
  EXPECT_NE(errorOf("format: lumistage-studio\nversion: 1\nrig: missing.yaml\n")
                .find("missing.yaml: cannot open"),
            std::string::npos);
  fs::remove_all(folder);
}

TEST(VirtualStudio, FramesCarryConsistentTruth) {
  const StudioConfig config = testing::referenceStudioOnRing(3000, 4, 512, 384);
  VirtualStudio studio(config, 10);
  ASSERT_GE(studio.clip().frames.size(), 10u);
  StudioFrame frame;
  for (int f : {0, 9}) {
    studio.renderFrame(f, frame);
    ASSERT_EQ(frame.images.size(), 4u);
    // Truth joints are the skeleton's joints in the clip's pose.
    std::vector<Eigen::Vector3d> expected;
    studio.actor().skeleton.jointPositions(studio.clip().sample(f / config.fps), expected);
    ASSERT_EQ(frame.joints.size(), expected.size());
    for (size_t j = 0; j < expected.size(); ++j)
      EXPECT_LT((frame.joints[j] - expected[j]).norm(), 1e-9);
    // The surface is the actor's, posed: its lowest point on the floor, its extent a person's.
    EXPECT_NEAR(frame.surface.positions.row(2).minCoeff(), 0.0, 0.04);
    EXPECT_GT(frame.surface.positions.row(2).maxCoeff(), 1.6);
    // Every camera sees the actor, and the masks are the images' alpha.
    for (int c = 0; c < 4; ++c) {
      size_t actor = 0;
      for (size_t p = 0; p < frame.masks[c].size(); ++p) {
        ASSERT_EQ(frame.masks[c][p], frame.images[c][4 * p + 3]);
        actor += frame.masks[c][p] > 0;
      }
      EXPECT_GT(actor, 2000u) << "camera " << c << " frame " << f;
    }
  }
}

}  // namespace
}  // namespace lumistage
