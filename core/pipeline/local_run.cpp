#include "core/pipeline/local_run.h"

#include <fmt/format.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <utility>

#include "core/base/error.h"
#include "core/body/human_model.h"
#include "core/body/human_skeleton.h"
#include "core/capture/session_reader.h"
#include "core/geometry/rig_file.h"
#include "core/net/curve_keys.h"

namespace lumistage {

namespace fs = std::filesystem;

namespace {

constexpr const char* kKeyStorePrefix = "lumistage_run_keys_";

// The temporary key stores of runs that died without removing them (SIGKILL, a crash, a power
// cut: their pid is gone): removed, so that their private keys do not stay in /tmp.
void removeStaleKeyStores() {
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(fs::temp_directory_path(), error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(kKeyStorePrefix, 0) != 0) continue;
    const pid_t pid = pid_t(std::atol(name.c_str() + std::strlen(kKeyStorePrefix)));
    if (pid <= 0 || (::kill(pid, 0) != 0 && errno == ESRCH)) fs::remove_all(entry.path(), error);
  }
}

// --body for the node processes: a body file's absolute path, whatever their working folder.
std::string bodyArgument(const BodyChoice& body) {
  return body.file.empty() ? bodyDetailName(body.detail) : fs::absolute(body.file).string();
}

}  // namespace

LocalPipelineRun::LocalPipelineRun(LocalRunOptions options) : options_(std::move(options)) {
  if (!options_.listen.empty()) {
    if (options_.rig.empty() || !options_.session.empty() || !options_.address.empty())
      throw Error("pipeline: nodes on the network need the rig file, and their own cameras");
    if (options_.keys.empty() && !options_.plain) {
      throw Error(
          "pipeline: nodes on the network need the key store they were given (lumistage keys "
          "init), or --plain on a closed network");
    }
  } else if (options_.session.empty() == (options_.rig.empty() || options_.address.empty())) {
    throw Error("pipeline: give a session, or a rig with the first camera's address");
  }
  std::optional<SessionReader> reader;
  if (!options_.session.empty()) reader.emplace(options_.session);
  rig_ = reader ? reader->rig() : loadRig(options_.rig);
  if (reader) frame_rate_ = reader->fps();
  options_.coordinator.raw_bytes_per_pixel =
      reader ? bytesPerPixel(reader->pixelFormat()) : 1;  // live: Bayer
  const int node_count =
      options_.nodes > 0 ? std::min(options_.nodes, rig_.nodeCount()) : rig_.nodeCount();
  for (int n = 0; n < node_count; ++n) names_.push_back(rig_.nodes()[n].name);

  StudioEndpointConfig endpoint;
  endpoint.bind = options_.listen.empty() ? "tcp://127.0.0.1:*" : options_.listen;
  keys_ = options_.keys;
  if (options_.plain) {
    endpoint.security = TransportSecurity::kPlain;
  } else {
    if (keys_.empty()) {
      removeStaleKeyStores();
      temporary_keys_ = true;
      keys_ = fs::temp_directory_path() /
              fmt::format("{}{}_{}", kKeyStorePrefix, ::getpid(), static_cast<void*>(this));
      KeyStore(keys_).init(names_, true);
    }
    const KeyStore store(keys_);
    endpoint.studio_key = store.studioKey();
    endpoint.authorized = store.authorizedNodes();
  }
  // The nodes pose the body chosen: the refinement's smoothness needs its triangles, the
  // visibility the studio sends them its posed and refined vertices.
  if (!options_.coordinator.body)
    options_.coordinator.body = std::make_shared<const SkinnedMesh>(loadBody(options_.body));
  studio_ =
      std::make_unique<StudioCoordinator>(rig_, endpoint, kHumanJointCount, options_.coordinator);

  if (nodesElsewhere()) return;  // they connect by themselves
  std::string node_binary = options_.node_binary.string();
  if (node_binary.empty())
    node_binary = (fs::read_symlink("/proc/self/exe").parent_path() / "lumistage-node").string();
  if (!fs::exists(node_binary)) throw Error("pipeline: no node program at " + node_binary);
  for (const std::string& name : names_) {
    std::vector<std::string> args = {node_binary, "--node", name, "--studio", studio_->endpoint()};
    if (options_.session.empty()) {
      args.insert(args.end(), {"--rig", options_.rig.string(), "--address", options_.address});
    } else {
      args.insert(args.end(),
                  {"--session", options_.session.string(), "--replay", options_.replay});
    }
    if (!options_.takes.empty()) args.insert(args.end(), {"--takes", options_.takes.string()});
    if (options_.plate_frames > 0)
      args.insert(args.end(), {"--plate-frames", std::to_string(options_.plate_frames)});
    args.insert(args.end(), {"--body", bodyArgument(options_.body)});
    if (options_.plain) {
      args.push_back("--plain");
    } else {
      args.insert(args.end(), {"--keys", keys_.string()});
    }
    std::vector<char*> argv;
    for (std::string& s : args) argv.push_back(s.data());
    argv.push_back(nullptr);
    const pid_t parent = ::getpid();
    const pid_t pid = fork();
    if (pid < 0) throw Error("pipeline: cannot start the process of node " + name);
    if (pid == 0) {
      // A node started here dies with this process, even when it crashes or is killed (a
      // destructor that never runs must not leave nodes replaying forever). The thread that
      // forked must outlive the run: the run is owned where it was made.
      prctl(PR_SET_PDEATHSIG, SIGTERM);
      if (::getppid() != parent) _exit(0);  // the parent already died before prctl
      // A process group of its own: a terminal's Ctrl-C reaches this process alone, which stops
      // the nodes in order (their takes closed first), not the nodes behind its back.
      ::setpgid(0, 0);
      execv(node_binary.c_str(), argv.data());
      _exit(127);
    }
    children_.push_back(pid);
    running_.push_back(true);
  }
}

LocalPipelineRun::~LocalPipelineRun() {
  for (size_t n = 0; n < children_.size(); ++n) {
    if (running_[n]) kill(children_[n], SIGTERM);
  }
  for (size_t n = 0; n < children_.size(); ++n) {
    if (running_[n]) waitpid(children_[n], nullptr, 0);
  }
  for (pid_t pid : killed_) waitpid(pid, nullptr, 0);
  std::error_code ec;
  if (temporary_keys_) fs::remove_all(keys_, ec);
}

void LocalPipelineRun::runFor(std::chrono::milliseconds duration) {
  studio_->runFor(duration);
  std::erase_if(killed_, [](pid_t pid) { return waitpid(pid, nullptr, WNOHANG) == pid; });
  for (size_t n = 0; n < children_.size(); ++n) {
    int status = 0;
    if (running_[n] && waitpid(children_[n], &status, WNOHANG) == children_[n]) {
      running_[n] = false;
      nodes_failed_ += !WIFEXITED(status) || WEXITSTATUS(status) != 0;
      exits_.push_back(fmt::format("node {} exited ({})", names_[n],
                                   WIFEXITED(status) ? fmt::format("status {}", WEXITSTATUS(status))
                                                     : fmt::format("signal {}", WTERMSIG(status))));
    }
  }
}

double LocalPipelineRun::frameRate() const {
  return reportedFrameRate().value_or(frame_rate_);
}

std::optional<double> LocalPipelineRun::reportedFrameRate() const {
  if (!options_.session.empty()) return frame_rate_;
  double sum = 0;
  int cameras = 0;
  for (const NodeReport& node : studio_->report().nodes) {
    for (const CameraHealth& camera : node.cameras) {
      // A rate measured over less than two seconds of frames is still settling: a node
      // replaying a 20 fps session on a loaded machine said 22 or 23 fps after its first second.
      if (node.lost || !(camera.frame_rate_hz > 0) || camera.frames < 2 * camera.frame_rate_hz)
        continue;
      sum += camera.frame_rate_hz;
      ++cameras;
    }
  }
  if (cameras == 0) return std::nullopt;
  return std::round(100 * sum / cameras) / 100;
}

void LocalPipelineRun::recordView(const std::filesystem::path& file,
                                  std::function<void(const std::string&)> stopped) {
  stopRecordingView();
  view_recorder_ = std::make_unique<ViewRecorder>(file, frameRate());
  view_recorder_failed_ = false;
  view_recorder_file_ = file;
  view_recorder_stopped_ = std::move(stopped);
  sinkBlendedViews();
}

void LocalPipelineRun::recordImage(const BlendedImage& image) {
  if (!view_recorder_ || view_recorder_failed_) return;
  try {
    if (view_recorder_->framesWritten() == 0) {
      const std::optional<double> fps = reportedFrameRate();
      if (!fps) return;  // no camera has measured its rate yet
      if (*fps != view_recorder_->fps())
        view_recorder_ = std::make_unique<ViewRecorder>(view_recorder_file_, *fps);
    }
    view_recorder_->add(image.frame_id, image.width, image.height, image.rgba);
  } catch (const std::exception& e) {
    view_recorder_failed_ = true;
    if (view_recorder_stopped_) view_recorder_stopped_(e.what());
  }
}

void LocalPipelineRun::feedView(const FeedTarget& target,
                                std::function<void(const std::string&)> stopped) {
  stopFeedingView();
  const ViewData& view = studio_->view();
  view_feed_ = std::make_unique<VideoFeed>(target, view.width, view.height, frameRate());
  view_feed_stopped_ = std::move(stopped);
  view_feed_told_ = false;
  sinkBlendedViews();
}

void LocalPipelineRun::feedImage(const BlendedImage& image) {
  if (!view_feed_ || view_feed_told_) return;
  // Premultiplied RGBA: the empty pixels are black, as in the recording.
  view_feed_->offer(image.width, image.height, image.rgba, PixelOrder::kRgba);
  if (const Status feeding = view_feed_->status(); !feeding.ok()) {
    view_feed_told_ = true;
    if (view_feed_stopped_) view_feed_stopped_(feeding.error());
  }
}

std::unique_ptr<VideoFeed> LocalPipelineRun::stopFeedingView() {
  std::unique_ptr<VideoFeed> feed = std::move(view_feed_);
  sinkBlendedViews();
  if (feed) feed->close();
  return feed;
}

void LocalPipelineRun::sinkBlendedViews() {
  if (!view_recorder_ && !view_feed_) {
    studio_->setBlendedSink({});
    return;
  }
  studio_->setBlendedSink([this](int view, const BlendedImage& image) {
    if (view != 0) return;
    recordImage(image);
    feedImage(image);
  });
}

std::unique_ptr<ViewRecorder> LocalPipelineRun::stopRecordingView() {
  std::unique_ptr<ViewRecorder> recorder = std::move(view_recorder_);
  sinkBlendedViews();
  if (recorder) recorder->close();
  return recorder;
}

void LocalPipelineRun::streamSkeleton(const OscTarget& target) {
  stopStreamingSkeleton();
  skeleton_stream_ = std::make_unique<VmcSender>(target, body().skeleton);
  studio_->setShownPoseSink(
      [sender = skeleton_stream_.get()](int64_t, const PoseData& pose, bool tracked) {
        sender->send(pose, tracked);
      });
}

void LocalPipelineRun::stopStreamingSkeleton() {
  studio_->setShownPoseSink({});
  skeleton_stream_.reset();
}

std::vector<std::string> LocalPipelineRun::takeExits() {
  return std::exchange(exits_, {});
}

double LocalPipelineRun::nodeCpuSeconds() const {
  double seconds = 0;
  const double ticks = double(sysconf(_SC_CLK_TCK));
  for (size_t n = 0; n < children_.size(); ++n) {
    if (!running_[n]) continue;
    // /proc/PID/stat: "pid (comm) state ..." with utime and stime the 14th and 15th fields; comm
    // may hold spaces, so count from its closing parenthesis.
    std::ifstream stat("/proc/" + std::to_string(children_[n]) + "/stat");
    std::string line;
    if (!std::getline(stat, line)) continue;
    const size_t close = line.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream fields(line.substr(close + 2));
    std::string field;
    unsigned long long utime = 0, stime = 0;
    for (int i = 3; i <= 15 && fields >> field; ++i) {
      if (i == 14) utime = std::stoull(field);
      if (i == 15) stime = std::stoull(field);
    }
    seconds += (utime + stime) / ticks;
  }
  return seconds;
}

bool LocalPipelineRun::anyNodeRunning() const {
  if (nodesElsewhere()) return true;
  for (bool r : running_) {
    if (r) return true;
  }
  return false;
}

bool LocalPipelineRun::nodeRunning(const std::string& name) const {
  if (nodesElsewhere()) return std::find(names_.begin(), names_.end(), name) != names_.end();
  for (size_t n = 0; n < names_.size(); ++n) {
    if (names_[n] == name) return running_[n];
  }
  return false;
}

bool LocalPipelineRun::killNode(const std::string& name) {
  for (size_t n = 0; n < names_.size(); ++n) {
    if (names_[n] != name || !running_[n]) continue;
    kill(children_[n], SIGKILL);
    // Reaped later (runFor, the destructor): a node's teardown (its OpenGL context, a session in
    // memory) takes a while on a loaded machine, and the studio's thread has frames to finish.
    killed_.push_back(children_[n]);
    running_[n] = false;
    exits_.push_back(fmt::format("node {} was stopped (killed)", name));
    return true;
  }
  return false;
}

}  // namespace lumistage
