// The command-line tools and the studio stopped by signals, as a terminal, a crash or a service
// manager stops them.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "core/base/atomic_file.h"
#include "core/render/video_file.h"
#include "tests/app/cli_test_util.h"

// Ctrl-C, SIGTERM and SIGHUP stop the programs in order: what they write is finished or removed,
// the processes they started are stopped, their temporary files go.
namespace lumistage {
namespace {

namespace fs = std::filesystem;

using testing::kCli;
using testing::Result;
using testing::run;
using testing::synthRingSession;
using testing::tempPath;

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

}  // namespace
}  // namespace lumistage
