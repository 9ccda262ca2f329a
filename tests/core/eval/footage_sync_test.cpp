// Cameras out of step found from masks of a walking actor: the virtual studio's actor rasterised
// into a ring of six cameras, two of them filmed frames early or late.
#include "core/eval/footage_sync.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "core/body/motion_library.h"
#include "core/geometry/ring_rig.h"
#include "tests/core/tracking/synthetic_stage.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

const std::string kStudio = std::string(LUMISTAGE_TEST_RESOURCE_DIR) + "/studio/reference.yaml";

Rig sixCameras() {
  RingRigSpec spec;
  spec.cameras = 6;
  spec.cameras_per_node = 3;
  spec.width = 640;
  spec.height = 480;
  return makeRingRig(spec);
}

// Masks (FOLDER/CAMERA/FFFFFF.png, full size) of the actor walking, `frames` footage frames at 30
// a second; camera c's footage frame f shows the walk at f - late[c].
void writeMasks(const Rig& rig, const fs::path& folder, int frames, const std::vector<int>& late) {
  testing::SyntheticStage stage(kStudio);
  const MotionClip clip = makeBuiltinClip("walk", stage.actor.skeleton, 30.0, 2.5);
  std::vector<Eigen::Affine3f> transforms;
  Eigen::Matrix3Xf positions, normals;
  LowResSilhouette cells;
  for (int c = 0; c < rig.cameraCount(); ++c) {
    const Camera& camera = rig.camera(c);
    fs::create_directories(folder / camera.name());
    for (int f = 0; f < frames; ++f) {
      const double t = std::max(0, f - late[size_t(c)] + 6) / 30.0;
      stage.actor.skeleton.skinningTransforms(clip.sample(t), transforms);
      skinMesh(stage.actor, transforms, positions, normals);
      rasterizeSilhouette(positions, stage.actor.rest.triangles, camera, c, 1, cells);
      cv::Mat mask(camera.height(), camera.width(), CV_8U, cv::Scalar(0));
      for (int y = 0; y < cells.height; ++y)
        for (int x = 0; x < cells.width; ++x)
          if (cells.at(x, y)) mask.at<uint8_t>(y, x) = 255;
      cv::imwrite((folder / camera.name() / fmt::format("{:06}.png", f)).string(), mask);
    }
  }
}

TEST(FootageSync, FindsTheCamerasFilmedEarlyOrLate) {
  const Rig rig = sixCameras();
  const fs::path folder = testing::testFolder("footage_sync");
  writeMasks(rig, folder, 24, {0, 0, 3, 0, -2, 0});
  FootageSyncOptions options;
  options.range = 4;
  const FootageSync sync = estimateFootageSync(rig, folder, options);
  ASSERT_EQ(sync.cameras.size(), 6u);
  const std::vector<int> expected = {0, 0, 3, 0, -2, 0};
  for (int c = 0; c < 6; ++c) EXPECT_EQ(sync.cameras[size_t(c)].offset, expected[size_t(c)]) << c;
  EXPECT_EQ(sync.spacing, 1);
  // In step, the hull explains nearly all of every mask; out of step, clearly less.
  EXPECT_GT(sync.agreement, 0.97);
  EXPECT_LT(sync.unshifted, sync.agreement - 0.02);
  EXPECT_LT(sync.cameras[2].unshifted, sync.cameras[2].agreement - 0.03);
  for (const FootageSyncCamera& c : sync.cameras) {
    if (!c.fixed) {
      EXPECT_GT(c.best_agreement, c.runner_up_agreement) << c.camera;
    }
  }
  EXPECT_NE(describeFootageSync(sync).find("+3"), std::string::npos);

  // A camera whose offset is given keeps it; the others are found against it. Masks every second
  // frame find offsets in steps of two.
  options.fixed = {{"cam05", -2}};
  for (int f = 1; f < 24; f += 2)
    for (const Camera& camera : rig.cameras())
      fs::remove(folder / camera.name() / fmt::format("{:06}.png", f));
  options.range = 4;
  const FootageSync given = estimateFootageSync(rig, folder, options);
  EXPECT_EQ(given.spacing, 2);
  EXPECT_TRUE(given.cameras[4].fixed);
  EXPECT_EQ(given.cameras[4].offset, -2);
  EXPECT_EQ(given.cameras[0].offset, 0);
  EXPECT_EQ(given.cameras[1].offset, 0);
  // Camera 3 at +3 is between +2 and +4: one of them.
  EXPECT_TRUE(given.cameras[2].offset == 2 || given.cameras[2].offset == 4)
      << given.cameras[2].offset;
  fs::remove_all(folder);
}

TEST(FootageSync, RefusesMasksThatAreNotTheRigs) {
  const Rig rig = sixCameras();
  const fs::path folder = testing::testFolder("footage_sync_bad");
  std::string e = testing::errorOf([&] { estimateFootageSync(rig, folder); });
  EXPECT_NE(e.find("no masks of camera 'cam01'"), std::string::npos) << e;
  writeMasks(rig, folder, 4, {0, 0, 0, 0, 0, 0});
  // A mask of another size than its camera's.
  cv::imwrite((folder / "cam03" / "000002.png").string(), cv::Mat(100, 100, CV_8U, cv::Scalar(0)));
  e = testing::errorOf([&] { estimateFootageSync(rig, folder); });
  EXPECT_NE(e.find("cam03/000002.png: a 100x100 mask"), std::string::npos) << e;
  // One that is not an image.
  std::ofstream(folder / "cam03" / "000002.png") << "not a png";
  e = testing::errorOf([&] { estimateFootageSync(rig, folder); });
  EXPECT_NE(e.find("cam03/000002.png: cannot read as an image"), std::string::npos) << e;
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lumistage
