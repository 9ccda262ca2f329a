// lumistage render, run as a user runs it: a video of the session along a camera path.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <string>

#include "core/base/atomic_file.h"
#include "core/render/video_file.h"
#include "tests/app/cli_test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

using testing::kCli;
using testing::Result;
using testing::run;
using testing::synthRingSession;
using testing::tempPath;

// lumistage render makes a video of the session along a camera path. A render that fails part way
// (here a mesh missing for the second frame) says so, leaves the video it would have replaced as
// it was, and no torn file beside it.
TEST(Cli, RenderWritesAVideoAndAFailedRenderReplacesNothing) {
  const fs::path folder = tempPath("render");
  ASSERT_TRUE(synthRingSession(folder, "--cameras 4 --width 320 --height 240",
                               "actor:\n  vertices: 2000\n", "--frames 3"));
  const fs::path session = folder / "session", video = folder / "orbit.mp4";
  const std::string common = kCli + " render --session " + session.string() +
                             " --width 160 --height 120 --out " + video.string() + " --mesh ";
  Result r = run(common + "truth");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto frames = [&] {
    cv::VideoCapture c(video.string());
    return c.isOpened() ? int(c.get(cv::CAP_PROP_FRAME_COUNT)) : -1;
  };
  ASSERT_EQ(frames(), 3);
  EXPECT_EQ(probeVideoFile(video).codec, "h264");  // .avi: Motion-JPEG (video_file_test)
  {
    cv::VideoCapture c(video.string());
    cv::Mat first;
    ASSERT_TRUE(c.read(first));
    EXPECT_EQ(first.cols, 160);
    double brightest = 0;
    cv::minMaxLoc(first.reshape(1), nullptr, &brightest);
    EXPECT_GT(brightest, 100) << "no actor in the video";
  }
  fs::create_directories(folder / "meshes");
  fs::copy_file(session / "truth" / "surface" / "000000.ply", folder / "meshes" / "000000.ply");
  r = run(common + (folder / "meshes").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("000001.ply"), std::string::npos) << r.output;
  EXPECT_EQ(frames(), 3);
  for (const auto& entry : fs::directory_iterator(folder))
    EXPECT_EQ(entry.path().filename().string().find(".partial"), std::string::npos) << entry.path();
  // Outputs over or inside the inputs are refused before any work, and the inputs are whole: a
  // render over one of the session's images, eval's report over its session.yaml (written over
  // it, exit 0, before).
  const std::string yaml = readFile(session / "session.yaml");
  const fs::path image = session / "cam01" / "000000.png";
  const uintmax_t image_bytes = fs::file_size(image);
  r = run(kCli + " render --session " + session.string() + " --out " + image.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("inside --session"), std::string::npos) << r.output;
  r = run(kCli + " render --session " + session.string() + " --out " + (folder / "x.png").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("expected a video file ending in .mp4 or .avi"), std::string::npos)
      << r.output;
  r = run(kCli + " eval --session " + session.string() + " --loo-frames 0 --quiet --json " +
          (session / "session.yaml").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--json " + (session / "session.yaml").string() + ": inside --session"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(readFile(session / "session.yaml"), yaml);
  EXPECT_EQ(fs::file_size(image), image_bytes);
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lumistage
