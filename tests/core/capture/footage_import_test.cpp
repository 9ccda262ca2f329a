#include "core/capture/footage_import.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "core/base/error.h"
#include "core/capture/session_reader.h"
#include "core/geometry/rig_import.h"
#include "core/geometry/ring_rig.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

fs::path testFolder() {
  const fs::path folder =
      fs::temp_directory_path() / ("lumistage_footage_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

// Frame i of camera c shows its number: a grey level of 10 i + c on the whole image.
cv::Mat numbered(int i, int c, int width, int height) {
  return cv::Mat(height, width, CV_8UC3, cv::Scalar::all(10 * i + c));
}

// The grey level at the centre of session frame k's camera c.
int levelOf(const SessionReader& session, int k, int c) {
  std::vector<CameraFrame> frames;
  session.readFrame(k, frames);
  const Image& image = frames[size_t(c)].image;
  return image.pixels[(size_t(image.height / 2) * image.width + image.width / 2) * 3];
}

// Videos and an image folder, each camera's frames counted exactly from the start: a camera given
// an offset of 3 shows its frame k + 3 beside the others' frame k, every second frame taken.
TEST(FootageImport, EveryCamerasFramesAreTakenExactlyAtItsOffset) {
  const fs::path folder = testFolder();
  RingRigSpec spec;
  spec.cameras = 3;
  spec.width = 160;
  spec.height = 120;
  const Rig rig = makeRingRig(spec);
  for (int c = 0; c < 2; ++c) {
    cv::VideoWriter video((folder / fmt::format("cam{:02}.avi", c + 1)).string(),
                          cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25, cv::Size(160, 120));
    ASSERT_TRUE(video.isOpened());
    for (int i = 0; i < 20; ++i) video.write(numbered(i, c, 160, 120));
  }
  fs::create_directories(folder / "cam03");
  for (int i = 0; i < 20; ++i)
    cv::imwrite((folder / "cam03" / fmt::format("{:04}.png", i)).string(),
                numbered(i, 2, 160, 120));
  FootageImportOptions options;
  options.first = 1;
  options.every = 2;
  const FootageImportReport report = importFootage(rig,
                                                   {{"cam01", folder / "cam01.avi", 0},
                                                    {"cam02", folder / "cam02.avi", 3},
                                                    {"cam03", folder / "cam03", -3}},
                                                   folder / "session", options);
  // cam03 begins 3 frames later: the first taken frame (1) has none, the next (3) its 0. cam02
  // runs out first: frame 1 + 2k + 3 <= 19 for k <= 7.
  EXPECT_EQ(report.frames, 7);
  ASSERT_EQ(report.notes.size(), 2u);
  EXPECT_NE(report.notes[0].find("camera 'cam02': its footage ends before its frame 20"),
            std::string::npos)
      << report.notes[0];
  EXPECT_NE(report.notes[1].find("1 frames left out at the start"), std::string::npos)
      << report.notes[1];
  const SessionReader session(folder / "session");
  ASSERT_EQ(session.frameCount(), 7);
  EXPECT_DOUBLE_EQ(session.fps(), 12.5);
  for (int k : {0, 3, 6}) {
    const int base = 3 + 2 * k;                                  // the footage's frame
    EXPECT_NEAR(levelOf(session, k, 0), 10 * base + 0, 2) << k;  // MJPEG: within 2
    EXPECT_NEAR(levelOf(session, k, 1), 10 * (base + 3) + 1, 2) << k;
    EXPECT_EQ(levelOf(session, k, 2), 10 * (base - 3) + 2) << k;  // PNG: exact
  }
  EXPECT_EQ(session.timestampNs(0), int64_t(2 * 1e9 / 25 + 0.5));  // the footage's time
  fs::remove_all(folder);
}

// Footage a few pixels narrower than its calibration (a video encoded 1080 wide for a 1088
// sensor) is taken as a crop; turned or foreign footage is refused, naming the file.
TEST(FootageImport, FootageSizesAgainstTheCalibration) {
  const fs::path folder = testFolder();
  RingRigSpec spec;
  spec.cameras = 1;
  spec.width = 168;
  spec.height = 120;
  const Rig rig = makeRingRig(spec);
  const auto folderOf = [&](const std::string& name, int width, int height) {
    fs::create_directories(folder / name);
    for (int i = 0; i < 2; ++i)
      cv::imwrite((folder / name / fmt::format("{}.png", i)).string(),
                  numbered(i, 0, width, height));
    return folder / name;
  };
  FootageImportOptions options;
  options.fps = 30;
  const FootageImportReport report =
      importFootage(rig, {{"cam01", folderOf("narrow", 160, 120), 0}}, folder / "s1", options);
  EXPECT_EQ(report.rig.camera(0).width(), 160);
  EXPECT_EQ(report.rig.camera(0).intrinsics(), rig.camera(0).intrinsics());
  EXPECT_NE(report.notes.at(0).find("cropped by 8 px at the right"), std::string::npos);
  EXPECT_EQ(SessionReader(folder / "s1").rig().camera(0).width(), 160);

  std::string e = testing::errorOf([&] {
    importFootage(rig, {{"cam01", folderOf("turned", 120, 168), 0}}, folder / "s2", options);
  });
  EXPECT_NE(e.find("turned a quarter"), std::string::npos) << e;
  e = testing::errorOf([&] {
    importFootage(rig, {{"cam01", folderOf("big", 320, 240), 0}}, folder / "s3", options);
  });
  EXPECT_NE(e.find("big: 320x240 pixels, camera 'cam01' is calibrated at 168x120"),
            std::string::npos)
      << e;
  e = testing::errorOf([&] {
    importFootage(rig, {{"cam01", folder / "missing.mp4", 0}}, folder / "s4", options);
  });
  EXPECT_NE(e.find("missing.mp4: no such video file or image folder"), std::string::npos) << e;
  std::ofstream(folder / "garbage.mp4") << "not a video";
  e = testing::errorOf([&] {
    importFootage(rig, {{"cam01", folder / "garbage.mp4", 0}}, folder / "s5", options);
  });
  EXPECT_NE(e.find("garbage.mp4: cannot open as a video"), std::string::npos) << e;
  fs::remove_all(folder);
}

// The Pose2Sim demo's four videos, a few frames: two of them 8 pixels narrower than calibrated.
TEST(FootageImport, ImportsThePose2SimDemosVideos) {
  const fs::path demo = testing::realData() / "pose2sim-walk";
  if (!fs::exists(demo / "videos" / "cam01.mp4")) GTEST_SKIP() << demo << " is not here";
  const fs::path folder = testFolder();
  const RigImport calibration = importQualisysRig(demo / "calibration" / "Calib.qca.txt", {});
  std::vector<FootageSource> sources;
  for (const Camera& camera : calibration.rig.cameras())
    sources.push_back({camera.name(), demo / "videos" / (camera.name() + ".mp4"), 0});
  sources[1].offset = 2;
  FootageImportOptions options;
  options.frames = 3;
  const FootageImportReport report =
      importFootage(calibration.rig, sources, folder / "walk", options);
  EXPECT_EQ(report.frames, 3);
  EXPECT_EQ(report.notes.size(), 2u);  // cam01 and cam02 cropped
  const SessionReader session(folder / "walk");
  EXPECT_DOUBLE_EQ(session.fps(), 60);
  EXPECT_EQ(session.rig().camera(0).width(), 1080);
  EXPECT_EQ(session.rig().camera(2).width(), 1088);
  std::vector<CameraFrame> frames;
  session.readFrame(2, frames);
  EXPECT_EQ(frames[3].image.height, 1920);
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lumistage
