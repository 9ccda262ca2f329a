// The command-line tools that set up a stage, run as a user runs them: rig show, rig ring and
// rig import, calibrate wand, keys, and a node checking its place in the rig.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/base/atomic_file.h"
#include "core/geometry/rig_file.h"
#include "core/geometry/ring_rig.h"
#include "core/net/curve_keys.h"
#include "tests/app/cli_test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

using testing::kCli;
using testing::kNode;
using testing::kReference;
using testing::Result;
using testing::run;
using testing::synthRingSession;
using testing::tempPath;

TEST(Cli, RigShowListsCamerasNodesAndCentres) {
  const Result r = run(kCli + " rig show " + kReference);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("12 cameras on 4 nodes"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("node node1"), std::string::npos);
  EXPECT_NE(r.output.find("cam12"), std::string::npos);
  EXPECT_NE(r.output.find("( 3.600,  0.000,  2.300)"), std::string::npos) << r.output;  // cam01
}

TEST(Cli, RigShowOfABadFileSaysWhereAndFails) {
  const fs::path bad = tempPath("bad.yaml");
  std::ofstream(bad) << "format: lumistage-rig\nversion: 1\nnodes: []\ncameras:\n  - name: c\n";
  const Result r = run(kCli + " rig show " + bad.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(
      r.output.find("lumistage: error: " + bad.string() + ":5: cameras[0].image_size: missing key"),
      std::string::npos)
      << r.output;
  fs::remove(bad);
}

TEST(Cli, KeysInitAndAddNodeWriteAKeyStoreTheStudioCanLoad) {
  const fs::path dir = tempPath("keys");
  fs::remove_all(dir);
  Result r = run(kCli + " keys init --dir " + dir.string() + " --nodes node1,node2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run(kCli + " keys add-node node3 --dir " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const KeyStore store(dir);
  EXPECT_TRUE(isZ85Key(store.studioKey().secret_key));
  const std::vector<AuthorizedNode> nodes = store.authorizedNodes();
  ASSERT_EQ(nodes.size(), 3u);
  EXPECT_EQ(nodes[2].public_key, store.nodeKey("node3").public_key);
  // A second init would lock every node out: refused, and the studio key is unchanged.
  const std::string studio = store.studioKey().public_key;
  r = run(kCli + " keys init --dir " + dir.string() + " --nodes node4");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("a studio key exists already"), std::string::npos) << r.output;
  EXPECT_EQ(store.studioKey().public_key, studio);
  fs::remove_all(dir);
}

TEST(Cli, RingThenImportOfSvobodaFilesRoundTrips) {
  // `rig ring` writes the reference rig; its cameras written out as MultiCamSelfCal files and
  // imported back give the same geometry.
  const fs::path ring = tempPath("ring.yaml");
  Result r = run(kCli + " rig ring --out " + ring.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Rig rig = loadRig(ring);
  EXPECT_TRUE(rig == makeRingRig({}));

  const fs::path folder = tempPath("svoboda");
  fs::create_directories(folder);
  for (int i = 0; i < rig.cameraCount(); ++i) {
    std::ofstream out(folder / ("camera" + std::to_string(i + 1) + ".Pmat.cal"));
    out.precision(17);
    const Eigen::Matrix<double, 3, 4> P = rig.camera(i).projectionMatrix();
    for (int row = 0; row < 3; ++row) out << P.row(row) << "\n";
  }
  const fs::path imported = tempPath("imported.yaml");
  r = run(kCli + " rig import --svoboda " + folder.string() + " --image-size 1024x768 --out " +
          imported.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("note: camera1: no .rad file"), std::string::npos) << r.output;
  const Rig back = loadRig(imported);
  ASSERT_EQ(back.cameraCount(), 12);
  for (int i = 0; i < 12; ++i) {
    EXPECT_LT((back.camera(i).centre() - rig.camera(i).centre()).norm(), 1e-9);
    EXPECT_EQ(back.nodeOfCamera(i), rig.nodeOfCamera(i));
  }

  r = run(kCli + " rig import --svoboda " + folder.string() + " --image-size 1024 --out " +
          imported.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("expected WIDTHxHEIGHT"), std::string::npos) << r.output;
  fs::remove_all(folder);
  fs::remove(ring);
  fs::remove(imported);
}

TEST(Cli, CalibrateWandSolvesASimulatedSessionAndWritesRigAndReport) {
  const fs::path folder = tempPath("wand");
  fs::create_directories(folder);
  const std::string points = (folder / "wand.txt").string();
  Result r = run(kCli + " calibrate synth-wand --samples 300 --seed 4 --out " + points +
                 " --multicamselfcal " + (folder / "mcsc").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(folder / "mcsc" / "points.dat"));
  const std::string rig = (folder / "rig.yaml").string(),
                    report = (folder / "report.yaml").string();
  r = run(kCli + " calibrate wand --points " + points + " --out " + rig + " --report " + report +
          " --truth " + kReference);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("camera centres: max"), std::string::npos) << r.output;
  EXPECT_EQ(loadRig(rig).cameraCount(), 12);
  std::ifstream in(report);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("method: wand"), std::string::npos);
  EXPECT_NE(text.find("coverage_fraction"), std::string::npos);

  // A solve that fits worse than --max-rms keeps the rig it would replace; its report, written
  // beside the rig where the studio looks for it by default, says why.
  const std::string kept = readFile(rig);
  fs::remove(report);
  r = run(kCli + " calibrate wand --points " + points + " --out " + rig + " --max-rms 0.01");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("is above --max-rms 0.01 px: the solve failed, " + rig +
                          " was not written (see " + (folder / "rig.calibration.yaml").string()),
            std::string::npos)
      << r.output;
  EXPECT_EQ(readFile(rig), kept);
  EXPECT_TRUE(fs::exists(folder / "rig.calibration.yaml"));
  // The rig or the report over the points it is solved from (the file one edits by hand): refused
  // before the solve, the points whole.
  const std::string wand_points = readFile(points);
  for (const std::string& outputs : {" --out " + points, " --out " + rig + " --report " + points}) {
    r = run(kCli + " calibrate wand --points " + points + outputs);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("it is --points " + points), std::string::npos) << r.output;
  }
  EXPECT_EQ(readFile(points), wand_points);

  // The points file with each line rewritten (none: left out), solved into NAME.yaml.
  const auto solveRewritten =
      [&](const std::string& name,
          const std::function<std::optional<std::string>(const std::string&)>& rewrite) {
        std::ifstream in(points);
        std::string line, text;
        while (std::getline(in, line))
          if (const std::optional<std::string> kept = rewrite(line)) text += *kept + "\n";
        std::ofstream(folder / (name + ".txt")) << text;
        return run(kCli + " calibrate wand --points " + (folder / (name + ".txt")).string() +
                   " --out " + (folder / (name + ".yaml")).string());
      };

  // Floor marks along one line leave the floor's tilt about it to noise: refused.
  int mark = 0;
  r = solveRewritten("line", [&](const std::string& line) -> std::optional<std::string> {
    if (line.rfind("floor ", 0) != 0) return line;
    std::istringstream words(line);
    std::string kind, sample;
    words >> kind >> sample;
    return "floor " + sample + " " + std::to_string(mark++) + " 0 0";
  });
  ASSERT_GE(mark, 3);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("floor marks lie (nearly) on a line"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(folder / "line.yaml"));

  // A camera that saw nothing: the error names it, and nothing is written.
  r = solveRewritten("dark", [](const std::string& line) -> std::optional<std::string> {
    if (line.rfind("point ", 0) == 0 && line.find(" cam07 ") != std::string::npos)
      return std::nullopt;
    return line;
  });
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("camera cam07 saw nothing"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(folder / "dark.yaml"));
  fs::remove_all(folder);
}

TEST(Cli, CalibrateWandFromAFilmedSessionThroughTheDetector) {
  const fs::path folder = tempPath("wand_session");
  fs::create_directories(folder);
  const std::string rig = (folder / "truth.yaml").string();
  Result r = run(kCli + " rig ring --cameras 8 --width 320 --height 240 --out " + rig);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run(kCli + " calibrate synth-wand --rig " + rig +
          " --samples 150 --noise-px 0 --outliers 0 " + "--out " + (folder / "w.txt").string() +
          " --session " + (folder / "dark").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run(kCli + " calibrate wand --session " + (folder / "dark").string() + " --out " +
          (folder / "rig.yaml").string() + " --truth " + rig + " --save-points " +
          (folder / "detected.txt").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("wand calibration: 153 samples"), std::string::npos) << r.output;
  EXPECT_EQ(loadRig(folder / "rig.yaml").cameraCount(), 8);
  // The detected points, to be completed with floor marks and solved again.
  r = run(kCli + " calibrate wand --points " + (folder / "detected.txt").string() + " --out " +
          (folder / "rig2.yaml").string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  fs::remove_all(folder);
}

TEST(Cli, NodeChecksItsPlaceInTheRig) {
  Result r = run(kNode + " --rig " + kReference + " --node node2");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("node node2"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("cam02"), std::string::npos);
  EXPECT_NE(r.output.find("cam06"), std::string::npos);
  r = run(kNode + " --rig " + kReference + " --node node9");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("no node 'node9'; the rig's nodes are: node1, node2, node3, node4"),
            std::string::npos)
      << r.output;
}

// A node replays a session whose cameras are not where --rig has them (cam01 and cam02 swapped):
// refused, naming both, instead of keying one camera's pictures with another's calibration.
TEST(Cli, ANodeRefusesASessionWhoseCamerasAreNotWhereItsRigHasThem) {
  const fs::path folder = tempPath("node_session_rig");
  ASSERT_TRUE(synthRingSession(folder, "--cameras 4 --width 160 --height 120",
                               "actor:\n  vertices: 2000\n", "--frames 1"));
  std::string text = readFile(folder / "session" / "rig.yaml");
  for (size_t at = 0; (at = text.find("cam0", at)) != std::string::npos; at += 5) {
    if (text[at + 4] == '1' || text[at + 4] == '2') text[at + 4] = text[at + 4] == '1' ? '2' : '1';
  }
  const fs::path swapped = folder / "swapped.yaml";
  writeFileAtomically(swapped, text);
  const Result r = run(kNode + " --rig " + swapped.string() + " --node node1 --session " +
                       (folder / "session").string() + " --studio tcp://127.0.0.1:9 --plain");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("camera 0 of --rig " + swapped.string() +
                          " is cam02 (160x120), the session's is cam01 (160x120)"),
            std::string::npos)
      << r.output;
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lumistage
