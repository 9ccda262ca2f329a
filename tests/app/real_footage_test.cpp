// The Pose2Sim demo (../shared/realdata/pose2sim-walk: four real cameras, a Qualisys calibration,
// a segmenter's masks at the even frames), a few frames of it, as a new user takes it: imported
// in one command, run through the distributed pipeline, and evaluated without ground truth.
// Skipped where the real data is not beside the repository.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "core/base/atomic_file.h"
#include "tests/app/cli_test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;
using namespace testing;

const fs::path kDemo =
    fs::path(LUMISTAGE_TEST_RESOURCE_DIR) / ".." / ".." / "shared" / "realdata" / "pose2sim-walk";

double number(const std::string& json, const std::string& key) {
  const size_t at = json.find("\"" + key + "\": ");
  return at == std::string::npos ? std::nan("") : std::stod(json.substr(at + key.size() + 4));
}

TEST(RealFootage, ThePose2SimDemoImportsRunsAndIsEvaluated) {
  if (!fs::exists(kDemo / "videos" / "cam01.mp4")) GTEST_SKIP() << kDemo << " is not here";
  const fs::path folder = tempPath("pose2sim");
  fs::remove_all(folder);
  // One command: the videos, the Qualisys calibration as it is, the masks of the even frames.
  Result r =
      run(kCli + " session import --rig " + (kDemo / "calibration" / "Calib.qca.txt").string() +
          " --footage " + (kDemo / "videos").string() + " --masks " + (kDemo / "masks").string() +
          " --frames 8 --out " + (folder / "walk").string());
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

}  // namespace
}  // namespace lumistage
