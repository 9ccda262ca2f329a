// lumistage run, run as a user runs it: real node processes, real files; and the options every
// command refuses before any work.
#include <gtest/gtest.h>
#include <sched.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "core/base/atomic_file.h"
#include "tests/app/cli_test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

using testing::freePort;
using testing::kCli;
using testing::kNode;
using testing::Result;
using testing::run;
using testing::synthRingSession;
using testing::tempPath;

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

// A node process that dies during a run (killed here, as by a crash): the run says which, still
// prints its figures, and exits with a failure, so that no script takes a run without that node
// for a measurement of the rig.
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
    // Where the frames' latency went: every part measured, the nodes' work and the fit taking
    // time, and together no more than the slowest frame's latency.
    const size_t parts = text.find("\"latency_parts_ms\": {");
    ASSERT_NE(parts, std::string::npos) << text;
    double sum = 0;
    for (const char* part : {"to_studio", "silhouettes", "mocap_queued", "mocap", "pose_out",
                             "statistics", "refine", "images", "blend"}) {
      const size_t at = text.find(std::string("\"") + part + "\": ", parts);
      ASSERT_NE(at, std::string::npos) << part << " in " << text;
      const double ms = std::stod(text.substr(at + std::strlen(part) + 4));
      EXPECT_GE(ms, 0.0) << part;
      sum += ms;
    }
    for (const char* part : {"mocap", "statistics", "images"}) {
      const size_t at = text.find(std::string("\"") + part + "\": ", parts);
      EXPECT_GT(std::stod(text.substr(at + std::strlen(part) + 4)), 0.0) << part << " in " << text;
    }
    const std::string p95_key = "\"latency_ms_p95\": ";
    const double p95 = std::stod(text.substr(text.find(p95_key) + p95_key.size()));
    EXPECT_GT(sum, 0.0);
    EXPECT_LE(sum, p95 * 1.5) << text;
    fs::remove(json);
  }
  fs::remove_all(folder);
}

// The whole pipeline, the studio and its node processes confined to one core and to two (as
// `taskset` confines them, and they inherit it), completes its frames: no hand-off waits on a
// thread that cannot run, no pool sized for cores it does not have starves the frame path.
// Whether frames complete, not how fast (speed is the benchmark's).
TEST(Cli, RunCompletesFramesConfinedToOneCoreAndToTwo) {
  cpu_set_t allowed;
  ASSERT_EQ(sched_getaffinity(0, sizeof(allowed), &allowed), 0);
  std::vector<int> cores;
  for (int c = 0; c < CPU_SETSIZE && cores.size() < 2; ++c)
    if (CPU_ISSET(c, &allowed)) cores.push_back(c);
  const fs::path folder = tempPath("cores");
  ASSERT_TRUE(synthRingSession(folder, "--cameras 4 --width 320 --height 240 --cameras-per-node 2",
                               "actor:\n  vertices: 2000\n", "--frames 6 --bayer"));
  for (size_t n = 1; n <= cores.size(); ++n) {
    std::string list = std::to_string(cores[0]);
    if (n == 2) list += "," + std::to_string(cores[1]);
    const fs::path json = folder / ("run-" + std::to_string(n) + ".json");
    const Result r =
        run("taskset -c " + list + " " + kCli + " run --session " + (folder / "session").string() +
            " --frames 12 --seconds 120 --json " + json.string());
    ASSERT_EQ(r.exit_code, 0) << "on " << n << " core(s): " << r.output;
    EXPECT_NE(r.output.find("12 frames in all"), std::string::npos) << r.output;
    const std::string text = readFile(json);
    const size_t fps = text.find("\"fps\": ");
    ASSERT_NE(fps, std::string::npos) << text;
    EXPECT_GT(std::stod(text.substr(fps + 7)), 0.0) << "on " << n << " core(s): " << text;
  }
  fs::remove_all(folder);
  if (cores.size() < 2) GTEST_SKIP() << "one core here: the two-core run left out";
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
