// `lumistage session import --repair-masks` and `lumistage session masks`: a segmenter's masks of
// footage without a green screen, repaired from a clean plate of each camera learnt from the take,
// the given ones kept. On a made-up take whose true masks are known (synthetic_take.h).
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "tests/app/cli_test_util.h"
#include "tests/core/imaging/synthetic_take.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;
using namespace testing;

std::string frameFile(int f) {
  return cv::format("%06d.png", f);
}

// folder/footage/CAMERA/ (images), folder/masks/CAMERA/ (the given masks) of two cameras filming
// made-up takes; the takes returned.
std::vector<SyntheticTake> writeFootage(const fs::path& folder) {
  std::vector<SyntheticTake> takes;
  for (int c = 0; c < 2; ++c) {
    SyntheticTakeSpec spec;
    spec.frames = 12;
    spec.torso_missing = {4, 5};
    spec.blob_frames = {2, 8};
    spec.planted_missing = {};
    spec.seed = uint32_t(11 + c);
    takes.push_back(makeSyntheticTake(spec));
    const std::string camera = cv::format("cam%02d", c + 1);
    fs::create_directories(folder / "footage" / camera);
    fs::create_directories(folder / "masks" / camera);
    for (int f = 0; f < spec.frames; ++f) {
      cv::Mat bgr;
      cv::cvtColor(takes.back().images[size_t(f)], bgr, cv::COLOR_RGB2BGR);
      cv::imwrite((folder / "footage" / camera / frameFile(f)).string(), bgr);
      cv::imwrite((folder / "masks" / camera / frameFile(f)).string(),
                  takes.back().given[size_t(f)]);
    }
  }
  return takes;
}

cv::Mat readMask(const fs::path& file) {
  return cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
}

// The mean IoU with the truth of the session's masks in `sub` (masks, masks-given).
double meanIou(const fs::path& session, const std::string& sub,
               const std::vector<SyntheticTake>& takes) {
  double sum = 0;
  int n = 0;
  for (size_t c = 0; c < takes.size(); ++c)
    for (size_t f = 0; f < takes[c].truth.size(); ++f, ++n)
      sum += iou(readMask(session / sub / cv::format("cam%02zu", c + 1) / frameFile(int(f))),
                 takes[c].truth[f]);
  return sum / n;
}

TEST(SessionMasks, ImportRepairsTheMasksAndKeepsTheGivenOnes) {
  const fs::path folder = tempPath("session_masks");
  fs::remove_all(folder);
  const std::vector<SyntheticTake> takes = writeFootage(folder);
  Result r = run(kCli + " rig ring --cameras 2 --width 320 --height 240 --out " +
                 (folder / "rig.yaml").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string import = kCli + " session import --rig " + (folder / "rig.yaml").string() +
                             " --footage " + (folder / "footage").string() + " --fps 30 --masks " +
                             (folder / "masks").string();
  r = run(import + " --repair-masks --out " + (folder / "s").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("imported 12 frames of 2 cameras"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("repaired the masks of 12 frames of 2 cameras:"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("cam02"), std::string::npos) << r.output;
  // The given masks, as they were; the repaired ones closer to the truth.
  for (size_t c = 0; c < takes.size(); ++c)
    for (size_t f = 0; f < takes[c].given.size(); ++f)
      EXPECT_EQ(
          cv::countNonZero(readMask(folder / "s" / "masks-given" / cv::format("cam%02zu", c + 1) /
                                    frameFile(int(f))) != takes[c].given[f]),
          0);
  const double given = meanIou(folder / "s", "masks-given", takes);
  const double repaired = meanIou(folder / "s", "masks", takes);
  EXPECT_GT(repaired, given + 0.05) << given;
  EXPECT_GT(repaired, 0.9) << given;
  EXPECT_FALSE(fs::exists(folder / "s" / "masks.repairing"));

  // Repaired again: from the given masks, to the same masks, the given ones untouched.
  const cv::Mat first = readMask(folder / "s" / "masks" / "cam01" / frameFile(4));
  r = run(kCli + " session masks --session " + (folder / "s").string() + " --pictures " +
          (folder / "pictures").string() + " --picture-every 6");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("repaired the masks of 12 frames of 2 cameras again"), std::string::npos)
      << r.output;
  EXPECT_EQ(cv::countNonZero(readMask(folder / "s" / "masks" / "cam01" / frameFile(4)) != first),
            0);
  EXPECT_NEAR(meanIou(folder / "s", "masks-given", takes), given, 1e-12);
  EXPECT_TRUE(fs::exists(folder / "pictures" / "cam02-000006.png"));
  EXPECT_FALSE(fs::exists(folder / "pictures" / "cam02-000005.png"));

  // Bad input: a camera without a mask to learn from, a session without masks, no masks given.
  r = run(import + " --out " + (folder / "plain").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  fs::remove_all(folder / "plain" / "masks" / "cam02");
  r = run(kCli + " session masks --session " + (folder / "plain").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("camera 'cam02': no frames to learn a plate from"), std::string::npos)
      << r.output;
  // The session as it was.
  EXPECT_TRUE(fs::exists(folder / "plain" / "masks" / "cam01" / frameFile(11)));
  EXPECT_FALSE(fs::exists(folder / "plain" / "masks-given"));
  EXPECT_FALSE(fs::exists(folder / "plain" / "masks.repairing"));
  fs::remove_all(folder / "plain" / "masks");
  r = run(kCli + " session masks --session " + (folder / "plain").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("the session has no masks/ to repair"), std::string::npos) << r.output;
  r = run(kCli + " session import --rig " + (folder / "rig.yaml").string() + " --footage " +
          (folder / "footage").string() + " --fps 30 --repair-masks --out " +
          (folder / "none").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--repair-masks: needs the actor's masks (--masks DIR)"),
            std::string::npos)
      << r.output;
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lumistage
