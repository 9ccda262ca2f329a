// The Pose2Sim demo (../shared/realdata/pose2sim-walk: four real cameras, a Qualisys calibration,
// a segmenter's masks at the even frames), a few frames of it, as a new user takes it: imported
// in one command, run through the distributed pipeline, and evaluated without ground truth.
// Skipped where the real data is not beside the repository.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "core/base/atomic_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;
using namespace testing;

const fs::path kDemo = testing::realData() / "pose2sim-walk";

double number(const std::string& json, const std::string& key) {
  const size_t at = json.find("\"" + key + "\": ");
  return at == std::string::npos ? std::nan("") : std::stod(json.substr(at + key.size() + 4));
}

// The demo imported in one command: the videos, the Qualisys calibration as it is, the masks of
// the even frames, and `options`.
Result importDemo(const std::string& options, const fs::path& out) {
  return run(kCli + " session import --rig " + (kDemo / "calibration" / "Calib.qca.txt").string() +
             " --footage " + (kDemo / "videos").string() + " --masks " +
             (kDemo / "masks").string() + " " + options + " --out " + out.string());
}

TEST(RealFootage, ThePose2SimDemoImportsRunsAndIsEvaluated) {
  if (!fs::exists(kDemo / "videos" / "cam01.mp4")) GTEST_SKIP() << kDemo << " is not here";
  const fs::path folder = tempPath("pose2sim");
  fs::remove_all(folder);
  Result r = importDemo("--frames 8", folder / "walk");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("imported 4 frames of 4 cameras"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("camera 'cam02': footage 1080x1920, calibrated 1088x1920"),
            std::string::npos)
      << r.output;
  // The distributed pipeline, its nodes keyed from the masks.
  r = run(kCli + " run --session " + (folder / "walk").string() +
          " --frames 2 --seconds 120 --json " + (folder / "run.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("2 frames in all"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("keyed from the session's masks"), std::string::npos) << r.output;
  // The quality report of a real take: the body against every camera's mask, every camera left
  // out and rendered from the other three.
  r = run(kCli + " eval --session " + (folder / "walk").string() + " --loo-frames 1 --json " +
          (folder / "eval.json").string() + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string json = readFile(folder / "eval.json");
  EXPECT_GE(number(json, "frames_tracked"), 2.0) << json;
  EXPECT_GT(number(json, "silhouette_iou"), 0.5) << json;
  EXPECT_NE(json.find("\"loo_masks\": \"given\""), std::string::npos) << json;
  EXPECT_GT(number(json, "loo_psnr_db"), 8.0) << json;
  EXPECT_LT(number(json, "loo_missed_pct"), 60.0) << json;
  fs::remove_all(folder);
}

// The segmenter's masks repaired from a clean plate of each camera, learnt from every sixth frame
// of the take: in cam04's frame 24 the given mask takes in the whole treadmill, the repaired one
// drops most of it. The given masks are kept as they came.
TEST(RealFootage, ThePose2SimDemosMasksAreRepairedAndTheGivenOnesKept) {
  if (!fs::exists(kDemo / "videos" / "cam01.mp4")) GTEST_SKIP() << kDemo << " is not here";
  const fs::path folder = tempPath("pose2sim_masks");
  fs::remove_all(folder);
  Result r = importDemo("--every 6 --frames 10 --repair-masks", folder / "walk");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("repaired the masks of 10 frames of 4 cameras"), std::string::npos)
      << r.output;
  for (const char* camera : {"cam01", "cam02", "cam03", "cam04"})
    EXPECT_NE(r.output.find(std::string("\n") + camera + " "), std::string::npos) << r.output;
  auto read = [](const fs::path& file) { return cv::imread(file.string(), cv::IMREAD_GRAYSCALE); };
  // Session frame k is the footage's frame 6k.
  for (int k = 0; k < 10; ++k) {
    const std::string name = cv::format("%06d.png", k), footage = cv::format("%06d.png", 6 * k);
    for (const char* camera : {"cam01", "cam04"})
      EXPECT_EQ(cv::countNonZero((read(kDemo / "masks" / camera / footage) > 127) !=
                                 read(folder / "walk" / "masks-given" / camera / name)),
                0)
          << camera << " " << name;
  }
  const cv::Mat given = read(folder / "walk" / "masks-given" / "cam04" / "000004.png");
  const cv::Mat repaired = read(folder / "walk" / "masks" / "cam04" / "000004.png");
  // Given: the treadmill and the man (494488 pixels); repaired: the man, and beside him what the
  // given masks take in so often that the plate is unknown there (195944).
  EXPECT_GT(cv::countNonZero(given), 400000);
  EXPECT_LT(cv::countNonZero(repaired), cv::countNonZero(given) / 2);
  EXPECT_GT(cv::countNonZero(repaired & given), 0.9 * cv::countNonZero(repaired));
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lumistage
