// The command-line tools run as a user runs them: real processes, real files.
#include <arpa/inet.h>
#include <assimp/scene.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <assimp/Importer.hpp>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "core/base/atomic_file.h"
#include "core/body/bvh.h"
#include "core/body/human_model.h"
#include "core/geometry/rig_file.h"
#include "core/geometry/ring_rig.h"
#include "core/net/curve_keys.h"
#include "core/render/video_file.h"
#include "tests/app/shell_command.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

using testing::Result;
using testing::run;

const std::string kCli = LUMISTAGE_CLI;
const std::string kNode = LUMISTAGE_NODE;
const std::string kReference = std::string(LUMISTAGE_TEST_RESOURCE_DIR) + "/rigs/reference.yaml";

// A TCP port on 127.0.0.1 that nothing listens on (the system's pick, released at once).
int freePort() {
  const int s = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t size = sizeof(address);
  if (s < 0 || ::bind(s, reinterpret_cast<sockaddr*>(&address), size) != 0 ||
      ::getsockname(s, reinterpret_cast<sockaddr*>(&address), &size) != 0) {
    ADD_FAILURE() << "no free port";
  }
  ::close(s);
  return ntohs(address.sin_port);
}

fs::path tempPath(const std::string& name) {
  return fs::temp_directory_path() / ("lumistage_cli_" + std::to_string(::getpid()) + "_" + name);
}

// folder/session: `lumistage synth <synth_options>` of a studio whose rig is `lumistage rig ring
// <rig_options>` (folder/rig.yaml) and whose other sections are `studio` (YAML).
::testing::AssertionResult synthRingSession(const fs::path& folder, const std::string& rig_options,
                                            const std::string& studio,
                                            const std::string& synth_options) {
  fs::create_directories(folder);
  Result r = run(kCli + " rig ring " + rig_options + " --out " + (folder / "rig.yaml").string());
  if (r.exit_code != 0) return ::testing::AssertionFailure() << r.output;
  std::ofstream(folder / "studio.yaml") << "format: lumistage-studio\nversion: 1\nrig: rig.yaml\n"
                                        << studio;
  r = run(kCli + " synth --config " + (folder / "studio.yaml").string() + " " + synth_options +
          " --out " + (folder / "session").string());
  if (r.exit_code != 0) return ::testing::AssertionFailure() << r.output;
  return ::testing::AssertionSuccess();
}

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

// Assimp's COLLADA parser recurses per nested node: 100,000 of them ended `body show` with
// SIGSEGV. The import runs in a child process: a crash inside it is an error naming the file,
// a refused file keeps its message, and a good file prints as before.
TEST(Cli, BodyShowSaysSoWhenTheImportCrashesOrIsRefused) {
  const fs::path deep = tempPath("deep.dae");
  {
    std::ofstream out(deep);
    out << "<?xml version=\"1.0\"?>\n<COLLADA xmlns=\"http://www.collada.org/2005/11/"
           "COLLADASchema\" version=\"1.4.1\">\n<library_visual_scenes><visual_scene id=\"s\">";
    for (int i = 0; i < 100000; ++i) out << "<node id=\"n\">";
    for (int i = 0; i < 100000; ++i) out << "</node>";
    out << "</visual_scene></library_visual_scenes><scene><instance_visual_scene url=\"#s\"/>"
           "</scene></COLLADA>\n";
  }
  Result r = run(kCli + " body show " + deep.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("lumistage: error: " + deep.string() +
                          ": the import crashed inside the mesh library"),
            std::string::npos)
      << r.output;
  const fs::path bad = tempPath("bad.fbx");
  std::ofstream(bad) << "garbage\n";
  r = run(kCli + " body show " + bad.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("lumistage: error: " + bad.string() + ": cannot read it as a mesh"),
            std::string::npos)
      << r.output;
  const fs::path good = tempPath("good.glb");
  ASSERT_EQ(run(kCli + " body generate --vertices 500 --out " + good.string()).exit_code, 0);
  r = run(kCli + " body show " + good.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("closed and manifold"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("24 joints:"), std::string::npos) << r.output;
  for (const fs::path& f : {deep, bad, good}) fs::remove(f);
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

// A node process that dies during a run (killed here, as by a crash): the run says which, still
// prints its figures, and exits with a failure, so that no script takes a run without that node
// for a measurement of the rig.
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

// Numbers out of range, or not numbers, are refused by option before any work: a run of 0 or NaN
// seconds exited 0 having done nothing, eval --cameras 1 tracked nobody, rig ring --cameras
// 2147483647 grew past a gigabyte, --max-rms nan failed a good solve.
TEST(Cli, NumbersOutOfRangeAreRefusedByTheirOption) {
  const struct {
    std::string command, message;
  } cases[] = {
      {" run --session /nonexistent --seconds nan",
       "--seconds: expected a number from 0.1 to 10000000, got nan"},
      {" stream --session /nonexistent --seconds 0", "--seconds: expected a number from 0.1"},
      {" eval --session /nonexistent --cameras 1", "--cameras: expected a number from 2 to 1000"},
      {" rig ring --cameras 2147483647 --out /nonexistent/r.yaml",
       "--cameras: expected a number from 1 to 256, got 2147483647"},
      {" calibrate wand --points /nonexistent --out /nonexistent/r.yaml --max-rms nan",
       "--max-rms: expected a number from 0.01 to 1000, got nan"},
      {" body generate --vertices 0 --out /nonexistent/b.glb",
       "--vertices: expected a number from 200 to 200000, got 0"},
      // A loop of the reference studio's 12 cameras that would not fit in memory, refused before
      // it renders for hours.
      {" virtual-cameras --config " + std::string(LUMISTAGE_TEST_RESOURCE_DIR) +
           "/studio/reference.yaml --frames 100000",
       "--frames 100000: 100000 frames of 12 cameras need"},
      // A generic human that is not shipped, and a body file that is not there.
      {" run --session /nonexistent/session --body coarse",
       "--body: 'coarse' is neither standard nor fine nor a file"},
      {" eval --session /nonexistent/session --body /nonexistent/actor.glb",
       "--body: '/nonexistent/actor.glb' is neither standard nor fine nor a file"},
      // Where a run would write, checked before it starts, not after its minute.
      {" run --session /nonexistent/session --json /nonexistent/r.json",
       "--json /nonexistent/r.json: no folder /nonexistent to write it into"},
  };
  for (const auto& c : cases) {
    const Result r = run(kCli + c.command);
    EXPECT_NE(r.exit_code, 0) << c.command;
    EXPECT_NE(r.output.find(c.message), std::string::npos) << c.command << "\n" << r.output;
  }
}

TEST(Cli, RunFailsWhenANodeProcessDies) {
  const fs::path folder = tempPath("node_dies");
  ASSERT_TRUE(synthRingSession(folder, "--cameras 2 --cameras-per-node 1 --width 320 --height 240",
                               "actor:\n  vertices: 2000\n", "--frames 4"));
  // ('[n]ode2': the pattern must not match this shell's own command line.)
  const Result r = run("(" + kCli + " run --session " + (folder / "session").string() +
                       " --frames 100000 --seconds 5 & sleep 2; pkill -9 -f -- '--node [n]ode2'; "
                       "wait $!)");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("node node2 exited (signal 9)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("frames in all"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("1 node process failed during the run"), std::string::npos) << r.output;
  fs::remove_all(folder);
}

// A PNG whose signature, header and end chunk are right (a session opens with it) but whose image
// data is garbage.
void garbleImageData(const fs::path& png) {
  std::string bytes = readFile(png);
  for (size_t i = 41; i + 20 < bytes.size(); ++i) bytes[i] = char(0x55);
  std::ofstream(png, std::ios::binary | std::ios::trunc) << bytes;
}

TEST(Cli, ADamagedImageCostsItsFrameAndAReplayThatCannotGoOnFails) {
  const fs::path folder = tempPath("damaged_image");
  ASSERT_TRUE(synthRingSession(folder, "--cameras 2 --cameras-per-node 1 --width 320 --height 240",
                               "actor:\n  vertices: 2000\n", "--frames 4"));
  const fs::path session = folder / "session";
  garbleImageData(session / "cam02" / "000001.png");
  // The stream goes on past it, says which file and counts the frame dropped.
  Result r = run(kCli + " stream --session " + session.string() + " --replay fast");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("cam02/000001.png"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("frame 1 skipped (counted as dropped)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("6 frames in"), std::string::npos) << r.output;
  // Every frame of a camera damaged: the stream stops, and says so in its status.
  for (const char* file : {"000000.png", "000002.png", "000003.png"})
    garbleImageData(session / "cam02" / file);
  r = run(kCli + " stream --session " + session.string() + " --replay fast");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("none of the session's 4 frames left can be decoded"), std::string::npos)
      << r.output;
  // A node replaying that camera stops with it, with a failure status, and so does the run.
  r = run(kCli + " run --session " + session.string() + " --frames 100000 --seconds 8");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("node node2 exited (status 1)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("1 node process failed during the run"), std::string::npos) << r.output;
  fs::remove_all(folder);
}

// A take onto a disk that fills (here: files may not grow past 40 blocks, about 20-40 KB, and a
// camera image is 77 KB): every node stops recording with an error, and the run says it failed.
TEST(Cli, RunFailsWhenATakeLosesANodesRecording) {
  const fs::path folder = tempPath("take_full_disk");
  ASSERT_TRUE(synthRingSession(folder, "--cameras 2 --cameras-per-node 1 --width 320 --height 240",
                               "actor:\n  vertices: 2000\n", "--frames 4 --bayer"));
  const Result r = run("(trap '' XFSZ; ulimit -f 40; " + kCli + " run --session " +
                       (folder / "session").string() + " --frames 20 --seconds 30 --record-take " +
                       (folder / "takes" / "take-1").string() + ")");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("take take-1: frames "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the take lost the recording of nodes node1, node2"), std::string::npos)
      << r.output;
  fs::remove_all(folder);
}

// --body fine: the studio and the nodes it starts pose the finer generic human alike (a node
// given offsets for another mesh says so and renders nothing), and each node sends the
// refinement twice the statistics.
TEST(Cli, RunPosesTheFineBodyInTheStudioAndItsNodes) {
  const fs::path folder = tempPath("fine_body");
  ASSERT_TRUE(synthRingSession(folder, "--cameras 4 --width 320 --height 240 --cameras-per-node 2",
                               "actor:\n  vertices: 2000\n", "--frames 6 --bayer"));
  std::map<std::string, double> bytes;
  for (const std::string body : {"standard", "fine"}) {
    const fs::path json = folder / (body + ".json");
    const Result r = run(kCli + " run --session " + (folder / "session").string() +
                         " --frames 12 --seconds 60 --body " + body + " --json " + json.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("12 frames in all"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("not used"), std::string::npos) << r.output;
    const std::string text = readFile(json);
    const size_t at = text.find("\"node_bytes_per_frame\": ");
    ASSERT_NE(at, std::string::npos) << text;
    bytes[body] = std::stod(text.substr(at + 24));
  }
  EXPECT_GT(bytes["fine"], 1.5 * bytes["standard"]) << bytes["fine"] << " " << bytes["standard"];
  fs::remove_all(folder);
}

// --body FILE (Khronos' CesiumMan from ../shared/realdata, where present): body show prints how
// its joints map onto ours; eval tracks with it; run starts nodes that pose the same file (a node
// posing another body would say its offsets are "not used").
TEST(Cli, TheActorsOwnBodyFromAFileIsShownEvaluatedAndRun) {
  const fs::path cesium = fs::path(LUMISTAGE_TEST_RESOURCE_DIR) / ".." / ".." / "shared" /
                          "realdata" / "bodies" / "CesiumMan.glb";
  if (!fs::exists(cesium)) GTEST_SKIP() << "no " << cesium.string();
  const Result shown = run(kCli + " body show " + cesium.string());
  ASSERT_EQ(shown.exit_code, 0) << shown.output;
  EXPECT_NE(shown.output.find("left_elbow      <- Skeleton_arm_joint_L__3_"), std::string::npos)
      << shown.output;
  const fs::path folder = tempPath("body_file");
  ASSERT_TRUE(synthRingSession(folder, "--cameras 4 --width 320 --height 240 --cameras-per-node 2",
                               "actor:\n  vertices: 2000\n", "--frames 6"));
  const Result eval = run(kCli + " eval --session " + (folder / "session").string() +
                          " --mocap-only --body " + cesium.string());
  ASSERT_EQ(eval.exit_code, 0) << eval.output;
  EXPECT_NE(eval.output.find("frames_tracked                        6"), std::string::npos)
      << eval.output;
  const Result r = run(kCli + " run --session " + (folder / "session").string() +
                       " --frames 12 --seconds 60 --body " + cesium.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("12 frames in all"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("not used"), std::string::npos) << r.output;
  // Exported as FBX: that body, skinned, on our skeleton (its vertices, not the generic human's).
  const Result exported =
      run(kCli + " export --session " + (folder / "session").string() + " --out " +
          (folder / "export").string() + " --fbx --unrefined --body " + cesium.string());
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  const std::string fbx = readFile(folder / "export" / "actor.fbx");
  EXPECT_NE(fbx.find(std::string("left_elbow\0\x01Model", 17)), std::string::npos);
  // The mesh's Vertices node: its array property ('d', then its length: three a vertex).
  const size_t at = fbx.find("Vertices");
  ASSERT_NE(at, std::string::npos);
  ASSERT_EQ(fbx[at + 8], 'd');
  uint32_t values = 0;
  std::memcpy(&values, fbx.data() + at + 9, 4);
  EXPECT_EQ(int(values), 3 * loadBody(parseBodyChoice(cesium.string())).rest.vertexCount());
  EXPECT_NE(int(values), 3 * loadGenericHuman().rest.vertexCount());
  fs::remove_all(folder);
}

// A screen lit a third as bright as the reference one: each node says which of its cameras sees
// it too dim to key cleanly, and runs on.
TEST(Cli, RunWarnsOfADimScreenNamingTheCamera) {
  const fs::path folder = tempPath("dim");
  ASSERT_TRUE(synthRingSession(
      folder, "--cameras 2 --width 320 --height 240",
      "actor:\n  vertices: 2000\nlook:\n  screen_green: [0.05, 0.17, 0.07]\n", "--frames 4"));
  // Long enough for the nodes to give up waiting for a brighter screen (30 frame sets).
  const Result r = run(kCli + " run --session " + (folder / "session").string() +
                       " --frames 100000 --seconds 4");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const std::string camera : {"cam01", "cam02"}) {
    // In the node's log, and in its camera's health as the studio shows it.
    EXPECT_NE(r.output.find("camera " + camera + ": green screen too dim to key cleanly"),
              std::string::npos)
        << r.output;
    const size_t health = r.output.find("      " + camera + " ");
    ASSERT_NE(health, std::string::npos) << r.output;
    EXPECT_NE(r.output.substr(health, r.output.find('\n', health) - health)
                  .find("green screen too dim to key cleanly"),
              std::string::npos)
        << r.output;
  }
  EXPECT_EQ(r.output.find("green screen learnt"), std::string::npos) << r.output;
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lumistage

namespace lumistage {
namespace {

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

}  // namespace
}  // namespace lumistage

namespace lumistage {
namespace {

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

// Footage and another tool's masks from elsewhere (here a virtual studio session's images and
// true masks, as image folders): imported in one command, then evaluated without a truth/.
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
  r = run(kCli + " eval --session " + (folder / "imported").string() + " --json " +
          (folder / "eval.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("no ground truth (truth/): motion capture's frames and silhouettes"),
            std::string::npos)
      << r.output;
  std::ifstream in(folder / "eval.json");
  const std::string json((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(json.find("\"frames_tracked\": 3"), std::string::npos) << json;
  const size_t at = json.find("\"silhouette_iou\": ");
  ASSERT_NE(at, std::string::npos) << json;
  EXPECT_GT(std::stod(json.substr(at + 18)), 0.6) << json.substr(at, 40);
  fs::remove_all(folder);
}

TEST(Cli, RunWritesTheFiguresAsJson) {
  const fs::path folder = tempPath("run");
  ASSERT_TRUE(synthRingSession(folder, "--cameras 4 --width 320 --height 240 --cameras-per-node 2",
                               "actor:\n  vertices: 2000\n", "--frames 6 --bayer"));
  for (const char* security : {"", " --plain"}) {
    const fs::path json = folder / "run.json", video = folder / "view.avi";
    // The plain run records a take too: its figures still count the 20 frames asked for, not
    // those the pipeline goes on with while the nodes close the take.
    const bool take = std::string(security) == " --plain";
    const std::string take_args =
        take ? " --record-take " + (folder / "takes" / "take-1").string() : "";
    const Result r = run(kCli + " run --session " + (folder / "session").string() +
                         " --frames 20 --seconds 30 --json " + json.string() + " --record-view " +
                         video.string() + security + take_args);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("20 frames in all"), std::string::npos) << r.output;
    if (take) {
      EXPECT_NE(r.output.find("take take-1: frames "), std::string::npos) << r.output;
      for (const char* node : {"node1", "node2"}) {
        EXPECT_NE(r.output.find(std::string("node ") + node + "    "), std::string::npos);
        EXPECT_TRUE(fs::exists(folder / "takes" / "take-1" / node / "index.csv")) << node;
      }
    }
    // Each node learnt its cameras' screen.
    EXPECT_NE(r.output.find("node node1: camera cam01: green screen learnt, key threshold"),
              std::string::npos)
        << r.output;
    // The view recorded as it was made (core/render/view_recorder_test reads such files back).
    const size_t recorded = r.output.find("recorded the view to " + video.string() + ": ");
    ASSERT_NE(recorded, std::string::npos) << r.output;
    // Frames late out of order are left out, gaps over a second (a slow start) not filled.
    EXPECT_GE(std::stoi(r.output.substr(r.output.find(": ", recorded) + 2)), 10) << r.output;
    const std::string avi = readFile(video);
    EXPECT_EQ(avi.substr(0, 4), "RIFF");
    EXPECT_EQ(avi.substr(8, 4), "AVI ");
    EXPECT_NE(avi.find("MJPG"), std::string::npos);
    fs::remove(video);
    EXPECT_NE(r.output.find("deadlines now: statistics "), std::string::npos) << r.output;
    const std::string text = readFile(json);
    for (const char* key :
         {"\"fps\": ", "\"latency_ms_p50\": ", "\"latency_ms_p95\": ", "\"stage_ms\": {",
          "\"node_bytes_per_frame\": ", "\"raw_bytes_per_frame_per_node\": 153600.0",
          "\"frames\": 20",
          "\"frames_dropped\": ", "\"frames_overtaken\": ", "\"frames_unshown\": ", "\"mocap\": ",
          "\"statistics_deadline_ms\": ", "\"image_deadline_ms\": ", "\"deadlines_following\": "}) {
      EXPECT_NE(text.find(key), std::string::npos) << key << " in " << text;
    }
    // The whole system's CPU a shown frame: the studio's and the nodes' processes, measured.
    const size_t cpu = text.find("\"cpu_ms_per_frame\": ");
    ASSERT_NE(cpu, std::string::npos) << text;
    EXPECT_GT(std::stod(text.substr(cpu + 20)), 1.0) << text.substr(cpu, 40);
    fs::remove(json);
  }
  fs::remove_all(folder);
}

// A real stage: the nodes run on their own PCs (here: processes started apart, as systemd would)
// and connect to a studio that listens for them, with the key store they were given.
// The frame rate an AVI's first stream header states (dwRate / dwScale); 0 when it has none.
double aviFrameRate(const std::string& avi) {
  const size_t at = avi.find("strh");
  if (at == std::string::npos || at + 36 > avi.size()) return 0;
  auto word = [&](size_t offset) {
    uint32_t v = 0;
    std::memcpy(&v, avi.data() + at + 8 + offset, 4);
    return v;
  };
  return word(20) > 0 ? double(word(24)) / word(20) : 0;
}

// The studio of a stage whose nodes run on other PCs, here processes started apart, cameras at
// 20 fps: it records the director's view at the rate they report, not at 30.
TEST(Cli, RunListensForNodesStartedOnTheStagesPCs) {
  const fs::path folder = tempPath("listen");
  ASSERT_TRUE(synthRingSession(folder, "--cameras 4 --width 320 --height 240 --cameras-per-node 2",
                               "actor:\n  vertices: 2000\nmotion:\n  clip: walk\n  fps: 20\n",
                               "--frames 6 --bayer"));
  const fs::path keys = folder / "keys";
  ASSERT_EQ(run(kCli + " keys init --dir " + keys.string() + " --nodes node1,node2").exit_code, 0);
  const std::string studio = "tcp://127.0.0.1:" + std::to_string(freePort());
  std::string nodes, pids;
  for (const char* node : {"node1", "node2"}) {
    nodes += kNode + " --node " + node + " --session " + (folder / "session").string() +
             " --studio " + studio + " --keys " + keys.string() + " > /dev/null 2>&1 & " + node +
             "=$!; ";
    pids += std::string(" $") + node;
  }
  const Result r = run(
      "(" + nodes + kCli + " run --rig " + (folder / "session/rig.yaml").string() + " --listen " +
      studio + " --keys " + keys.string() + " --record-view " + (folder / "view.avi").string() +
      " --frames 70 --seconds 40; status=$?; kill" + pids + "; wait; exit $status)");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NEAR(aviFrameRate(readFile(folder / "view.avi")), 20, 1.5) << r.output;
  EXPECT_NE(r.output.find("studio at " + studio + " (CURVE), waiting for the rig's 2 nodes"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("70 frames in all"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("node node2    streaming"), std::string::npos) << r.output;
  // Without the key store the nodes have, nobody could join: said before listening.
  const Result no_keys = run(kCli + " run --rig " + (folder / "session/rig.yaml").string() +
                             " --listen " + studio + " --frames 1 --seconds 1");
  EXPECT_NE(no_keys.exit_code, 0);
  EXPECT_NE(no_keys.output.find("need the key store they were given"), std::string::npos)
      << no_keys.output;
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lumistage

namespace lumistage {
namespace {

// The number after "key": in a flat JSON report; NaN when the key is missing.
double reportNumber(const std::string& text, const std::string& key) {
  const size_t at = text.find("\"" + key + "\": ");
  return at == std::string::npos ? std::nan("") : std::stod(text.substr(at + key.size() + 4));
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

TEST(Cli, ExportWritesTheCaptureAsBvhGltfAndPlyThatReadBack) {
  const fs::path folder = tempPath("export");
  const fs::path session = folder / "session", out = folder / "export";
  ASSERT_TRUE(synthRingSession(folder, "--cameras 8 --width 640 --height 480",
                               "actor:\n  vertices: 2000\n", "--frames 5"));
  Result r = run(kCli + " export --session " + session.string() + " --out " + out.string() +
                 " --bvh --fbx --glb --ply");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("5 frames exported"), std::string::npos) << r.output;

  // The BVH reads back onto the generic skeleton, a frame per session frame.
  const SkinnedMesh generic = loadGenericHuman();
  const MotionClip clip = loadBvh(out / "skeleton.bvh", generic.skeleton);
  EXPECT_EQ(clip.frames.size(), 5u);
  // The FBX (binary, for Blender: core/body/fbx_export_test reads such files back): every joint
  // of the generic skeleton as a skeleton node, the skinned body, one take.
  const std::string fbx = readFile(out / "actor.fbx");
  EXPECT_EQ(fbx.substr(0, 20), "Kaydara FBX Binary  ");
  for (const Joint& joint : generic.skeleton.joints())
    EXPECT_NE(fbx.find(joint.name + std::string("\0\x01Model", 7)), std::string::npos)
        << joint.name;
  EXPECT_NE(fbx.find(std::string("body\0\x01Model", 11)), std::string::npos);
  EXPECT_NE(fbx.find("AnimStack"), std::string::npos);
  // The animated glTF: a mesh of the generic human's size per frame, a node animation.
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile((out / "surface.glb").string(), 0);
  ASSERT_NE(scene, nullptr) << importer.GetErrorString();
  ASSERT_EQ(scene->mNumMeshes, 5u);
  EXPECT_EQ(int(scene->mMeshes[4]->mNumVertices), generic.rest.vertexCount());
  EXPECT_EQ(scene->mNumAnimations, 1u);
  // The refined surface stands where the actor does: on the floor, about the actor's height (this
  // actor is the generic human, 1.74 m; glTF is Y up). The tracker needs the cameras' low-res
  // silhouettes to resolve the limbs: 640x480 here, not less.
  float low = 1e9f, high = -1e9f;
  for (unsigned v = 0; v < scene->mMeshes[4]->mNumVertices; ++v) {
    low = std::min(low, scene->mMeshes[4]->mVertices[v].y);
    high = std::max(high, scene->mMeshes[4]->mVertices[v].y);
  }
  EXPECT_NEAR(low, 0.0f, 0.08f);
  EXPECT_NEAR(high - low, 1.74f, 0.1f);
  EXPECT_TRUE(fs::exists(out / "meshes" / "000004.ply"));

  // The last frame's image of a camera cut short (the disk filled): the session ends before it,
  // and the command says so, naming the file, instead of exporting one frame less in silence.
  const fs::path cut = session / "cam03" / "000004.png";
  fs::resize_file(cut, fs::file_size(cut) / 2);
  r = run(kCli + " export --session " + session.string() + " --out " +
          (folder / "export_cut").string() + " --bvh");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("4 frames exported"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("cam03/000004.png"), std::string::npos) << r.output;

  // A session nobody can be tracked in: a clear error, nothing half-written claimed.
  r = run(kCli + " export --session " + (folder / "nothing").string() + " --out " +
          (folder / "export2").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("nothing"), std::string::npos) << r.output;
  fs::remove_all(folder);
}

}  // namespace
}  // namespace lumistage

// Ctrl-C, SIGTERM and SIGHUP stop the programs in order: what they write is finished or removed,
// the processes they started are stopped, their temporary files go.
namespace lumistage {
namespace {

// A program started as from a terminal: a process group of its own (the terminal's foreground
// job, which its Ctrl-C reaches whole), the signals' default actions, its output to a file.
// Killed with its group however the test ends.
class Started {
 public:
  Started(std::vector<std::string> args, const fs::path& log,
          const std::vector<std::pair<std::string, std::string>>& environment = {})
      : log_(log) {
    pid_ = fork();
    if (pid_ == 0) {
      ::setpgid(0, 0);
      for (const int signal : {SIGINT, SIGTERM, SIGHUP}) std::signal(signal, SIG_DFL);
      for (const auto& [name, value] : environment) ::setenv(name.c_str(), value.c_str(), 1);
      const int out = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(out, STDOUT_FILENO);
      dup2(out, STDERR_FILENO);
      std::vector<char*> argv;
      for (std::string& arg : args) argv.push_back(arg.data());
      argv.push_back(nullptr);
      execv(argv[0], argv.data());
      _exit(127);
    }
    ::setpgid(pid_, pid_);  // (also here: the test may signal the group before the child runs)
  }
  ~Started() {
    if (pid_ <= 0) return;
    ::kill(-pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
  }
  pid_t pid() const { return pid_; }
  std::string output() const {
    std::ifstream in(log_);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }
  // Whether the output says `text` within `seconds`.
  bool waitForOutput(const std::string& text, double seconds) const {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
      if (output().find(text) != std::string::npos) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  }
  // The exit code once it ends within `seconds`; -(the signal) if a signal ended it; 1000 if it
  // did not end.
  int waitForExit(double seconds) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return 1000;
  }

 private:
  fs::path log_;
  pid_t pid_ = -1;
};

// The processes whose command line holds `text`.
int processesWith(const std::string& text) {
  int count = 0;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream in(entry.path() / "cmdline");
    std::string line((std::istreambuf_iterator<char>(in)), {});
    std::replace(line.begin(), line.end(), '\0', ' ');
    count += line.find(text) != std::string::npos;
  }
  return count;
}

// The temporary key stores a run made for its nodes (LocalPipelineRun) that are still there.
int temporaryKeyStores(pid_t pid) {
  int count = 0;
  const std::string prefix = "lumistage_run_keys_" + std::to_string(pid) + "_";
  for (const auto& entry : fs::directory_iterator(fs::temp_directory_path()))
    count += entry.path().filename().string().rfind(prefix, 0) == 0;
  return count;
}

// Ctrl-C in the terminal of a run that records a take and the view: the terminal signals the
// run's process group; the run stops its nodes itself, after they closed the take, finishes the
// view's video, reports, and removes the key store it made.
TEST(Cli, RunStoppedByCtrlCClosesItsTakeAndVideoAndStopsItsNodes) {
  const fs::path folder = tempPath("ctrl_c");
  ASSERT_TRUE(synthRingSession(folder, "--cameras 4 --width 320 --height 240 --cameras-per-node 2",
                               "actor:\n  vertices: 2000\n", "--frames 6 --bayer"));
  // The view as H.264 (RunWritesTheFiguresAsJson records Motion-JPEG).
  const fs::path video = folder / "view.mp4", take = folder / "takes" / "take-1";
  Started pipeline(
      {kCli, "run", "--session", (folder / "session").string(), "--frames", "100000", "--seconds",
       "120", "--record-view", video.string(), "--record-take", take.string()},
      folder / "pipeline.log");
  for (const char* node : {"node1", "node2"}) {
    ASSERT_TRUE(pipeline.waitForOutput(std::string("node ") + node + ": recording take take-1", 60))
        << pipeline.output();
  }
  ASSERT_EQ(temporaryKeyStores(pipeline.pid()), 1) << "the run's own key store, while it runs";
  // Once the nodes have told their disks, the run says how long the fullest lasts (the two share
  // this machine's disk); a few frame sets are in the take by then.
  ASSERT_TRUE(pipeline.waitForOutput("take: the fullest node's disk (node", 30))
      << pipeline.output();
  EXPECT_NE(pipeline.output().find(" min of takes"), std::string::npos) << pipeline.output();
  ASSERT_EQ(::kill(-pipeline.pid(), SIGINT), 0);
  ASSERT_EQ(pipeline.waitForExit(60), 0) << pipeline.output();
  const std::string out = pipeline.output();
  EXPECT_NE(out.find("lumistage run: stopped by SIGINT (Ctrl-C) after "), std::string::npos) << out;
  EXPECT_NE(out.find("take take-1: frames "), std::string::npos) << out;
  EXPECT_EQ(out.find("not closed"), std::string::npos) << out;
  for (const char* node : {"node1", "node2"}) {
    EXPECT_NE(out.find(std::string("node ") + node + ": sent "), std::string::npos) << out;
    // Each node's log says where its takes go, and the room there.
    const size_t told = out.find(std::string("node ") + node + ": takes go to " +
                                 (folder / "takes").string() + " (");
    EXPECT_NE(told, std::string::npos) << out;
    EXPECT_NE(out.substr(told, out.find('\n', told) - told).find(" free)"), std::string::npos);
    const std::string index = readFile(take / node / "index.csv");
    EXPECT_GE(std::count(index.begin(), index.end(), '\n'), 3) << node << ": " << index;
  }
  EXPECT_NE(out.find("recorded the view to " + video.string()), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(folder / "view.partial.mp4"));
  EXPECT_EQ(probeVideoFile(video).codec, "h264");
  cv::VideoCapture capture(video.string(), cv::CAP_FFMPEG);
  cv::Mat first;
  EXPECT_TRUE(capture.read(first)) << "the view's video does not read back";
  EXPECT_EQ(temporaryKeyStores(pipeline.pid()), 0);
  EXPECT_EQ(processesWith((folder / "session").string()), 0) << "a node is left running";
  // The parts join into a session: the take is whole.
  const Result merged =
      run(kCli + " session merge " + take.string() + " --out " + (folder / "merged").string());
  EXPECT_EQ(merged.exit_code, 0) << merged.output;
  fs::remove_all(folder);
}

// A run recording the view is killed outright (SIGKILL, as a crash or a power cut would end it):
// its partial video is recovered whole by lumistage video recover, and the next recording under
// the name is made beside it rather than over it.
TEST(Cli, AViewRecordingThatNeverClosedIsRecovered) {
  const fs::path folder = tempPath("killed_recording");
  ASSERT_TRUE(synthRingSession(folder, "--cameras 4 --width 320 --height 240 --cameras-per-node 2",
                               "actor:\n  vertices: 2000\n", "--frames 6 --bayer"));
  const fs::path video = folder / "view.avi", partial = folder / "view.partial.avi";
  // The run, recording the view; `frames` for how many.
  const auto runArgs = [&](const std::string& frames) {
    return std::vector<std::string>{kCli,
                                    "run",
                                    "--session",
                                    (folder / "session").string(),
                                    "--frames",
                                    frames,
                                    "--seconds",
                                    "120",
                                    "--record-view",
                                    video.string()};
  };
  pid_t killed = -1;
  {
    Started pipeline(runArgs("100000"), folder / "run.log");
    killed = pipeline.pid();
    ASSERT_TRUE(pipeline.waitForOutput("node node2: camera cam02: green screen", 60))
        << pipeline.output();
    // Frames enough to pass the video writer's buffer.
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (std::chrono::steady_clock::now() < end &&
           (!fs::exists(partial) || fs::file_size(partial) < 300'000))
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    ASSERT_EQ(::kill(-pipeline.pid(), SIGKILL), 0);
    EXPECT_EQ(pipeline.waitForExit(30), -SIGKILL);
  }
  ASSERT_TRUE(fs::exists(partial));
  EXPECT_FALSE(fs::exists(video));
  EXPECT_EQ(temporaryKeyStores(killed), 1) << "what a killed run cannot remove";
  const Result r = run(kCli + " video recover " + partial.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path recovered = folder / "view-recovered.avi";
  EXPECT_NE(r.output.find("recovered "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" fps) into " + recovered.string()), std::string::npos) << r.output;
  const int frames = std::stoi(r.output.substr(r.output.find("recovered ") + 10));
  EXPECT_GT(frames, 5) << r.output;
  cv::VideoCapture capture(recovered.string(), cv::CAP_OPENCV_MJPEG);
  ASSERT_TRUE(capture.isOpened());
  EXPECT_EQ(int(capture.get(cv::CAP_PROP_FRAME_COUNT)), frames);
  cv::Mat last;
  for (int f = 0; f < frames; ++f) ASSERT_TRUE(capture.read(last)) << "frame " << f;
  // Recording again to the name: the run says what it keeps, and records beside it.
  const uintmax_t left = fs::file_size(partial);
  std::string again;
  for (const std::string& arg : runArgs("20")) again += arg + " ";
  const Result second = run(again);
  ASSERT_EQ(second.exit_code, 0) << second.output;
  EXPECT_NE(second.output.find(partial.string() + ", left by a recording that never closed, is "
                                                  "kept (lumistage video recover"),
            std::string::npos)
      << second.output;
  EXPECT_EQ(fs::file_size(partial), left);
  EXPECT_TRUE(fs::exists(video));
  // The next run removed the killed one's key store (its process is gone): no private keys left.
  EXPECT_EQ(temporaryKeyStores(killed), 0);
  fs::remove_all(folder);
}

// Ctrl-C during a render: no torn video is left, and the command says it did not finish.
TEST(Cli, RenderStoppedByCtrlCLeavesNoVideo) {
  const fs::path folder = tempPath("render_ctrl_c");
  ASSERT_TRUE(synthRingSession(folder, "--cameras 4 --width 320 --height 240",
                               "actor:\n  vertices: 2000\n", "--frames 120"));
  const fs::path video = folder / "orbit.mp4";
  // 1920x1080: the render's 120 frames take seconds, the signal a moment.
  Started render({kCli, "render", "--session", (folder / "session").string(), "--width", "1920",
                  "--height", "1080", "--out", video.string()},
                 folder / "render.log");
  // (The progress goes to stderr, unbuffered: a tenth of the frames rendered.)
  ASSERT_TRUE(render.waitForOutput("render: 12/120", 60)) << render.output();
  ASSERT_EQ(::kill(-render.pid(), SIGINT), 0);
  ASSERT_EQ(render.waitForExit(60), 1) << render.output();
  EXPECT_NE(render.output().find("stopped by SIGINT (Ctrl-C) after "), std::string::npos)
      << render.output();
  EXPECT_NE(render.output().find(" of 120 frames: nothing written"), std::string::npos)
      << render.output();
  EXPECT_FALSE(fs::exists(video));
  for (const auto& entry : fs::directory_iterator(folder))
    EXPECT_EQ(entry.path().filename().string().find(".partial"), std::string::npos) << entry.path();
  fs::remove_all(folder);
}

#ifdef LUMISTAGE_STUDIO
// SIGTERM to the studio (a logout, a service manager) closes it as its close button does: the
// pipeline's nodes stopped in order, its key store removed, the window's layout remembered.
TEST(Cli, StudioStoppedBySigtermClosesAsItsWindowWould) {
  const fs::path folder = tempPath("studio_sigterm");
  ASSERT_TRUE(synthRingSession(folder, "--cameras 4 --width 320 --height 240 --cameras-per-node 2",
                               "actor:\n  vertices: 2000\n", "--frames 6 --bayer"));
  Started studio(
      {LUMISTAGE_STUDIO, "--source", "none", "--pipeline", (folder / "session").string()},
      folder / "studio.log",
      {{"QT_QPA_PLATFORM", "offscreen"}, {"XDG_CONFIG_HOME", (folder / "config").string()}});
  for (const char* node : {"node1", "node2"}) {
    ASSERT_TRUE(studio.waitForOutput(std::string("node ") + node + ": 2 cameras, serving", 60))
        << studio.output();
  }
  ASSERT_EQ(temporaryKeyStores(studio.pid()), 1) << studio.output();
  ASSERT_EQ(::kill(studio.pid(), SIGTERM), 0);
  ASSERT_EQ(studio.waitForExit(60), 0) << studio.output();
  const std::string out = studio.output();
  EXPECT_NE(out.find("lumistage-studio: stopped by SIGTERM; closing"), std::string::npos) << out;
  for (const char* node : {"node1", "node2"})
    EXPECT_NE(out.find(std::string("node ") + node + ": sent "), std::string::npos) << out;
  EXPECT_EQ(temporaryKeyStores(studio.pid()), 0);
  EXPECT_EQ(processesWith((folder / "session").string()), 0) << "a node is left running";
  EXPECT_NE(readFile(folder / "config" / "Lumistage" / "Studio.conf").find("geometry"),
            std::string::npos);
  fs::remove_all(folder);
}
#endif

}  // namespace
}  // namespace lumistage
