// lumistage synth, footage import and eval, run as a user runs them: sessions of the virtual
// studio and footage from elsewhere, scored against the truth or without one.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "core/base/atomic_file.h"
#include "core/body/human_skeleton.h"
#include "core/geometry/rig_file.h"
#include "tests/app/cli_test_util.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

using testing::kCli;
using testing::Result;
using testing::run;
using testing::synthRingSession;
using testing::tempPath;

TEST(Cli, SynthWritesACompleteSession) {
  // A small stage: 4 cameras at 320x240, 3 frames, Bayer.
  const fs::path folder = tempPath("synth");
  fs::create_directories(folder);
  Result r = run(kCli + " rig ring --cameras 4 --width 320 --height 240 --out " +
                 (folder / "rig.yaml").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ofstream(folder / "studio.yaml")
      << "format: lumistage-studio\nversion: 1\nrig: rig.yaml\n"
         "actor:\n  clothing: true\n  vertices: 2500\nmotion:\n  clip: crouch\n";
  const fs::path session = folder / "session";
  r = run(kCli + " synth --config " + (folder / "studio.yaml").string() +
          " --frames 3 --bayer --out " + session.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("wrote 3 frames"), std::string::npos) << r.output;
  const Rig rig = loadRig(session / "rig.yaml");
  EXPECT_EQ(rig.cameraCount(), 4);
  std::ifstream index(session / "index.csv");
  std::string line;
  int lines = 0;
  while (std::getline(index, line)) ++lines;
  EXPECT_EQ(lines, 4);  // header and three frames
  for (const char* file :
       {"session.yaml", "contact_sheet.png", "cam01/000000.png", "cam04/000002.png",
        "truth/joints.csv", "truth/masks/cam02/000001.png", "truth/surface/000002.ply"}) {
    EXPECT_TRUE(fs::exists(session / file)) << file;
  }
  // Bayer: one channel of the camera's size (checked from the PNG header: width, height, grey).
  std::ifstream png(session / "cam01" / "000000.png", std::ios::binary);
  unsigned char header[26];
  png.read(reinterpret_cast<char*>(header), 26);
  EXPECT_EQ((header[16] << 24) | (header[17] << 16) | (header[18] << 8) | header[19], 320);
  EXPECT_EQ((header[20] << 24) | (header[21] << 16) | (header[22] << 8) | header[23], 240);
  EXPECT_EQ(header[25], 0);  // colour type 0: greyscale

  // Never over an existing session.
  r = run(kCli + " synth --config " + (folder / "studio.yaml").string() + " --frames 1 --out " +
          session.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("already exists and is not empty"), std::string::npos) << r.output;
  fs::remove_all(folder);
}

// A stage drawn from a seed: its config is written beside the session and films the same stage
// again; the corpus runs the seeds it is given and reports them.
TEST(Cli, SynthDrawsAStageFromASeedThatItsConfigFilmsAgain) {
  const fs::path folder = tempPath("seed");
  fs::remove_all(folder);
  Result r =
      run(kCli + " synth --seed 11 --cameras 4-4 --frames 1 --out " + (folder / "drawn").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("stage 11: 4 cameras"), std::string::npos) << r.output;
  ASSERT_TRUE(fs::exists(folder / "drawn" / "studio.yaml"));
  r = run(kCli + " synth --config " + (folder / "drawn" / "studio.yaml").string() +
          " --frames 1 --out " + (folder / "again").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto bytes = [](const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_EQ(bytes(folder / "drawn" / "truth" / "joints.csv"),
            bytes(folder / "again" / "truth" / "joints.csv"));
  EXPECT_EQ(bytes(folder / "drawn" / "rig.yaml"), bytes(folder / "again" / "rig.yaml"));

  r = run(kCli + " synth --seed 3 --config " + (folder / "drawn" / "studio.yaml").string() +
          " --out " + (folder / "both").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("excludes"), std::string::npos) << r.output;
  r = run(kCli + " corpus --seeds 9-3 --out " + (folder / "corpus").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("--seeds '9-3': expected a number or a range FIRST-LAST"),
            std::string::npos)
      << r.output;
  r = run(kCli + " corpus --seeds 4,2 --cameras 4-4 --frames 2 --out " +
          (folder / "corpus").string() + " --json " + (folder / "corpus.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("2 stages: MPJPE mean"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(folder / "corpus" / "seed-4" / "studio.yaml"));
  EXPECT_TRUE(fs::exists(folder / "corpus" / "seed-2" / "index.csv"));
  EXPECT_NE(bytes(folder / "corpus.json").find("\"stages\": 2"), std::string::npos);
  fs::remove_all(folder);
}

// The number after "key": in a flat JSON report; NaN when the key is missing.
double reportNumber(const std::string& text, const std::string& key) {
  const size_t at = text.find("\"" + key + "\": ");
  return at == std::string::npos ? std::nan("") : std::stod(text.substr(at + key.size() + 4));
}

// Footage and another tool's masks from elsewhere (here a virtual studio session's images and
// true masks, as image folders): imported in one command, then evaluated without a truth/: motion
// capture, and every camera left out and rendered from the others over the given masks, or over
// the green key where a session carries no masks.
TEST(Cli, ImportedFootageWithMasksIsTrackedAndEvaluatedWithoutTruth) {
  const fs::path folder = tempPath("import");
  fs::remove_all(folder);
  Result r = run(kCli + " synth --seed 5 --cameras 8-8 --start clip --frames 4 --out " +
                 (folder / "studio").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // Every other frame's masks only: the import takes the frames that have them.
  fs::remove(folder / "studio" / "truth" / "masks" / "cam03" / "000001.png");
  r = run(kCli + " session import --rig " + (folder / "studio" / "rig.yaml").string() +
          " --footage " + (folder / "studio").string() + " --fps 30 --masks " +
          (folder / "studio" / "truth" / "masks").string() + " --out " +
          (folder / "imported").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("1 frames left out: a camera has no mask of them"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("imported 3 frames of 8 cameras"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(folder / "imported" / "masks" / "cam08" / "000002.png"));
  // The cameras' offsets from the masks: filmed together, none.
  r = run(kCli + " session sync --rig " + (folder / "studio" / "rig.yaml").string() + " --masks " +
          (folder / "studio" / "truth" / "masks").string() + " --range 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("session import options: (none: in step)"), std::string::npos)
      << r.output;
  r = run(kCli + " session import --rig " + (folder / "studio" / "rig.yaml").string() +
          " --footage " + (folder / "studio").string() + " --fps 30 --sync --out " +
          (folder / "unsynced").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--sync: needs the actor's masks (--masks DIR)"), std::string::npos)
      << r.output;
  r = run(kCli + " eval --session " + (folder / "imported").string() + " --loo-frames 1 --json " +
          (folder / "eval.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("no ground truth (truth/): motion capture's frames and silhouettes, "
                          "and every camera's view rendered from the others over its given masks"),
            std::string::npos)
      << r.output;
  std::ifstream in(folder / "eval.json");
  const std::string json((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(json.find("\"frames_tracked\": 3"), std::string::npos) << json;
  EXPECT_GT(reportNumber(json, "silhouette_iou"), 0.6) << json;
  EXPECT_NE(json.find("\"loo_masks\": \"given\""), std::string::npos) << json;
  EXPECT_EQ(reportNumber(json, "loo_frames"), 1.0) << json;
  // The refined body renders the views left out better than the posed one, as on the truth.
  const double given = reportNumber(json, "loo_psnr_db");
  EXPECT_GT(given, 15.0) << json;
  EXPECT_GT(given, reportNumber(json, "loo_psnr_db_unrefined") + 1.5) << json;
  EXPECT_FALSE(std::isnan(reportNumber(json, "loo_psnr_db_cam08"))) << json;
  EXPECT_LT(reportNumber(json, "loo_missed_pct_cam01"), 20.0) << json;
  EXPECT_EQ(json.find("truth_surface"), std::string::npos) << json;  // needs the truth
  EXPECT_EQ(json.find("mpjpe_mm"), std::string::npos) << json;
  // The virtual studio's own take without its truth: scored over each image's green key.
  const fs::path keyed = folder / "keyed";
  fs::copy(folder / "studio", keyed, fs::copy_options::recursive);
  fs::remove_all(keyed / "truth");
  std::string yaml = readFile(keyed / "session.yaml");
  yaml.replace(yaml.find("truth: true"), 11, "truth: false");
  std::ofstream(keyed / "session.yaml") << yaml;
  r = run(kCli + " eval --session " + keyed.string() + " --loo-frames 1 --json " +
          (folder / "keyed.json").string() + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("over its keyed masks"), std::string::npos) << r.output;
  std::ifstream keyed_in(folder / "keyed.json");
  const std::string keyed_json((std::istreambuf_iterator<char>(keyed_in)), {});
  EXPECT_NE(keyed_json.find("\"loo_masks\": \"keyed\""), std::string::npos) << keyed_json;
  EXPECT_EQ(reportNumber(keyed_json, "loo_frames"), 1.0) << keyed_json;
  EXPECT_GT(reportNumber(keyed_json, "loo_psnr_db"), 15.0) << keyed_json;
  EXPECT_GT(reportNumber(keyed_json, "loo_psnr_db"),
            reportNumber(keyed_json, "loo_psnr_db_unrefined") + 1.5)
      << keyed_json;
  EXPECT_LT(reportNumber(keyed_json, "loo_missed_pct"), 20.0) << keyed_json;
  fs::remove_all(folder);
}

// An actor holding an A-pose still, filmed by 6 cameras (the development corpus's seed 1): his
// outline is the same facing either way, and the fit's cost cannot tell his front from his back.
// Where the two fit as well, the feet decide: from the first frame he is tracked facing the way his
// toes point (before: 386 mm in every frame, every joint of his left on his right).
TEST(Cli, AStillActorSeenByFewCamerasIsTrackedFacingTheWayHisFeetPoint) {
  const fs::path motions = testing::realData() / "motions";
  if (!fs::exists(motions)) GTEST_SKIP() << motions << " is not here (the seed draws from it)";
  const fs::path folder = tempPath("still");
  fs::remove_all(folder);
  Result r = run(kCli + " synth --seed 1 --cameras 4-6 --motions " + motions.string() +
                 " --frames 12 --out " + (folder / "session").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_NE(readFile(folder / "session" / "studio.yaml").find("clip: a_pose_hold"),
            std::string::npos);
  r = run(kCli + " eval --session " + (folder / "session").string() + " --mocap-only --json " +
          (folder / "eval.json").string() + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string json = readFile(folder / "eval.json");
  int checked = 0;
  for (size_t at = json.find("{\"frame\": 0"); at != std::string::npos;
       at = json.find("{\"frame\": ", at + 1)) {
    const std::string row = json.substr(at, json.find('}', at) - at);
    EXPECT_LT(reportNumber(row, "mpjpe_mm"), 60.0) << row;
    ++checked;
  }
  EXPECT_EQ(checked, 12) << json;
  fs::remove_all(folder);
}

// Every stage scored against the virtual studio's truth, each in its place: the pipeline's
// refined mesh renders the left-out views better than the unrefined one and worse than the true
// surface, the refinement brings the mesh to the truth, the key finds the actor.
TEST(Cli, EvalScoresEachStageAgainstTheTruth) {
  const fs::path folder = tempPath("eval"), session = folder / "session";
  ASSERT_TRUE(synthRingSession(folder, "--cameras 8 --width 640 --height 480",
                               "actor:\n  clothing: true\n  vertices: 2000\n", "--frames 8"));
  const fs::path json = folder / "eval.json", pictures = folder / "views";
  const Result r = run(kCli + " eval --session " + session.string() + " --loo-frames 1 --json " +
                       json.string() + " --loo-pictures " + pictures.string() + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string text = readFile(json);
  // Every camera's scored view beside its image and their error map, cropped to the actor.
  int pictures_written = 0;
  for (const auto& entry : fs::directory_iterator(pictures)) {
    const cv::Mat picture = cv::imread(entry.path().string());
    ASSERT_FALSE(picture.empty()) << entry.path();
    EXPECT_EQ(picture.cols % 3, 0) << entry.path();
    EXPECT_LT(picture.cols, 3 * 640) << entry.path();
    EXPECT_EQ(entry.path().extension(), ".png");
    ++pictures_written;
  }
  EXPECT_EQ(pictures_written, 8);
  // A pictures folder that cannot be made, or pictures of no view, are refused before any work.
  Result refused = run(kCli + " eval --session " + session.string() + " --loo-pictures " +
                       json.string() + "/views --quiet");
  EXPECT_EQ(refused.exit_code, 1) << refused.output;
  EXPECT_NE(refused.output.find("cannot create"), std::string::npos) << refused.output;
  refused = run(kCli + " eval --session " + session.string() + " --loo-frames 0 --loo-pictures " +
                pictures.string() + " --quiet");
  EXPECT_EQ(refused.exit_code, 1) << refused.output;
  EXPECT_NE(refused.output.find("--loo-frames 0"), std::string::npos) << refused.output;
  EXPECT_LT(reportNumber(text, "key_missed_pct"), 0.5) << text;
  EXPECT_EQ(reportNumber(text, "key_extra_pct"), 0.0) << text;
  EXPECT_EQ(reportNumber(text, "frames_tracked"), 8.0) << text;
  EXPECT_LT(reportNumber(text, "mpjpe_mm"), 50.0) << text;
  // Each joint's error, over the same frames: their mean is the MPJPE, and no joint's height is
  // further off than the joint itself.
  for (const char* joint : {"pelvis", "head", "right_ankle", "left_hand"}) {
    const double error = reportNumber(text, std::string("joint_error_mm_") + joint),
                 height = reportNumber(text, std::string("joint_height_error_mm_") + joint);
    EXPECT_GT(error, 0.0) << joint << "\n" << text;
    EXPECT_LE(std::abs(height), error + 1e-9) << joint << "\n" << text;
  }
  const Skeleton skeleton = makeHumanSkeleton();
  double joints_mean = 0;
  for (const auto& joint : skeleton.joints())
    joints_mean += reportNumber(text, "joint_error_mm_" + joint.name) / skeleton.jointCount();
  EXPECT_NEAR(joints_mean, reportNumber(text, "mpjpe_mm"), 1e-3) << text;  // 6 digits in JSON
  EXPECT_EQ(reportNumber(text, "loo_frames"), 1.0) << text;
  const double unrefined = reportNumber(text, "loo_psnr_db_unrefined"),
               refined = reportNumber(text, "loo_psnr_db"),
               strict = reportNumber(text, "loo_psnr_db_strict"),
               best = reportNumber(text, "loo_psnr_db_best_offsets"),
               truth = reportNumber(text, "loo_psnr_db_truth_surface");
  EXPECT_GT(refined, unrefined + 3.0) << text;
  EXPECT_GT(truth, refined + 1.5) << text;
  EXPECT_NEAR(strict, refined, 1.0) << text;
  EXPECT_GT(best, unrefined + 3.0) << text;
  EXPECT_LT(best, truth) << text;
  EXPECT_LT(reportNumber(text, "surface_mm_refined"),
            0.5 * reportNumber(text, "surface_mm_unrefined"))
      << text;
  EXPECT_FALSE(std::isnan(reportNumber(text, "loo_psnr_db_cam08"))) << text;
  // Which way the refinement's offsets miss the best ones: most vertices within a few millimetres
  // of theirs, the percentiles in order and agreeing with the shares beyond 2 mm either way.
  const double p10 = reportNumber(text, "loo_offset_error_mm_p10"),
               p50 = reportNumber(text, "loo_offset_error_mm_p50"),
               p90 = reportNumber(text, "loo_offset_error_mm_p90"),
               inward = reportNumber(text, "loo_offset_inward_pct"),
               outward = reportNumber(text, "loo_offset_outward_pct");
  EXPECT_LE(p10, p50) << text;
  EXPECT_LE(p50, p90) << text;
  EXPECT_LT(std::abs(p50), 2.0) << text;
  EXPECT_LT(inward + outward, 70.0) << text;
  EXPECT_EQ(p10 < -2.0, inward >= 10.0) << text;
  EXPECT_EQ(p90 > 2.0, outward >= 10.0) << text;
  // The matte score also counts what is drawn beyond the actor; the true surface misses nothing.
  // (Its 2000 vertices here, rim-dilated, draw beyond the actor too, and the view's feathered
  // silhouette, whose odds are the pipeline geometry's, costs the true one: the pipeline's refined
  // mesh comes within half a dB of it or above it (0.75 dB above since the tracker fits the
  // silhouettes' edges); the strict one, carved by no silhouette of its view, about 1 dB below the
  // refined.)
  const double truth_matte = reportNumber(text, "loo_matte_psnr_db_truth_surface"),
               refined_matte = reportNumber(text, "loo_matte_psnr_db");
  EXPECT_GT(refined_matte, truth_matte - 0.5) << text;
  EXPECT_GT(refined_matte, reportNumber(text, "loo_matte_psnr_db_strict") + 0.5) << text;
  EXPECT_LT(reportNumber(text, "loo_missed_pct_truth_surface"), 0.5) << text;
  EXPECT_GT(reportNumber(text, "loo_missed_pct_unrefined"), reportNumber(text, "loo_missed_pct"))
      << text;
  EXPECT_GT(reportNumber(text, "loo_beyond_pct"), 0.0) << text;
  // The unrefined generic mesh leaves much of the actor undrawn: a large share of its error lies
  // there, more than of the refined mesh's.
  EXPECT_GT(reportNumber(text, "loo_missed_error_pct_unrefined"),
            reportNumber(text, "loo_missed_error_pct"))
      << text;
  EXPECT_GT(reportNumber(text, "loo_missed_error_pct_unrefined"), 30.0) << text;

  // A camera whose view holds no actor (its truth masks empty) has nothing to score over the
  // mask: null, and the means are the other cameras' (not pulled down by a 0 dB).
  for (const auto& entry : fs::directory_iterator(session / "truth" / "masks" / "cam08")) {
    cv::Mat mask = cv::imread(entry.path().string(), cv::IMREAD_GRAYSCALE);
    mask.setTo(0);
    ASSERT_TRUE(cv::imwrite(entry.path().string(), mask));
  }
  const Result again = run(kCli + " eval --session " + session.string() +
                           " --loo-frames 1 --json " + json.string() + " --quiet");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  const std::string without = readFile(json);
  EXPECT_NE(without.find("\"loo_psnr_db_cam08\": null"), std::string::npos) << without;
  double others = 0;
  for (int c = 1; c <= 7; ++c) others += reportNumber(text, fmt::format("loo_psnr_db_cam{:02}", c));
  EXPECT_NEAR(reportNumber(without, "loo_psnr_db"), others / 7, 1e-3) << without;
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lumistage
