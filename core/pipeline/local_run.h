#pragma once

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/body/human_model.h"
#include "core/live/video_feed.h"
#include "core/live/vmc_sender.h"
#include "core/pipeline/studio_coordinator.h"
#include "core/render/view_recorder.h"

namespace lumistage {

struct LocalRunOptions {
  // The nodes' cameras: a recorded session, or live Aravis cameras (rig + first address).
  std::filesystem::path session;
  std::filesystem::path rig;
  std::string address;
  std::string replay = "rate";        // session pace: rate or memory
  int nodes = 0;                      // the rig's first N nodes; 0: all
  bool plain = false;                 // no CURVE
  std::filesystem::path keys;         // key store; empty: fresh keys in a temporary folder
  std::filesystem::path node_binary;  // lumistage-node; empty: beside this executable
  std::filesystem::path takes;        // where the nodes record takes; empty: none
  int plate_frames = 0;  // the nodes learn clean plates from their first N sets (CameraNodeOptions)
  // The human the studio and the nodes it starts pose: the generic human or a file, whose path
  // the nodes are given (nodes on the stage's PCs are given theirs by their own --body); unused
  // when coordinator.body is set.
  BodyChoice body;
  // Nodes on the stage's PCs instead (lumistage-node --studio, e.g. from its systemd unit): the
  // studio listens here (e.g. tcp://*:5570) for the rig's nodes and starts no node process; needs
  // `rig` and the key store they were given (or `plain`).
  std::string listen;
  StudioCoordinatorOptions coordinator;
};

// The whole distributed pipeline on one machine: the studio's coordinator in this process and a
// lumistage-node process per rig node, with keys. What `lumistage run` and the studio's pipeline
// panel drive. Node processes that exit are reported (their own messages go to stderr); the rest
// go on. With `listen`, the studio's side alone, for nodes running on the stage's PCs.
class LocalPipelineRun {
 public:
  // Throws Error naming what is missing (session, rig, keys) or what cannot start (a listen
  // address already in use).
  explicit LocalPipelineRun(LocalRunOptions options);
  ~LocalPipelineRun();  // stops the nodes, removes temporary keys
  LocalPipelineRun(const LocalPipelineRun&) = delete;
  LocalPipelineRun& operator=(const LocalPipelineRun&) = delete;

  // Works for `duration` (or until the coordinator's max_frames), then looks after the nodes.
  void runFor(std::chrono::milliseconds duration);
  // "node node3 exited (status 1)" for each node that exited since the last call.
  std::vector<std::string> takeExits();
  // How many node processes ended on a signal or a failure status (not stopped by killNode).
  int nodesFailed() const { return nodes_failed_; }
  // Whether a node process started here still runs (always, for nodes on other PCs).
  bool anyNodeRunning() const;
  // CPU time (user + system, seconds) the running node processes have used so far.
  double nodeCpuSeconds() const;
  // Whether the process of a node is still running (false for a name not run here; true for a
  // node on another PC: the studio's node state says whether it streams).
  bool nodeRunning(const std::string& name) const;
  // Kills a node's process at once (SIGKILL), as pulling its plug would stop it: what a test or a
  // technician uses to check that the studio notices. False when it is not running.
  bool killNode(const std::string& name);
  bool nodesElsewhere() const { return !options_.listen.empty(); }

  // The cameras' frame rate: the session's; for live cameras, the mean of the rates the nodes
  // report (rounded to a hundredth) once measured over two seconds of frames, or 30 before.
  double frameRate() const;
  // The same, none while live cameras have not measured theirs yet.
  std::optional<double> reportedFrameRate() const;

  // Records the director's view (view 0), every blended image as it is made, to `file`
  // (ViewRecorder), at the cameras' rate; replaces a recording under way. The recorder is made
  // now, so that a file that cannot be written throws Error here, and made again at the first
  // image when the rate is another by then: live cameras measure theirs after the run starts
  // (images before are left out). A failure while recording (a full disk) stops the recording,
  // not the pipeline, and is given to `stopped`.
  void recordView(const std::filesystem::path& file,
                  std::function<void(const std::string&)> stopped = {});
  // Streams the skeleton of every frame shown to `target` in the VMC protocol (VmcSender: an OSC
  // bundle a frame, sent without waiting), the pose its images were rendered with; replaces a
  // stream under way. Throws Error when the host does not resolve.
  void streamSkeleton(const OscTarget& target);
  void stopStreamingSkeleton();
  const VmcSender* skeletonStream() const { return skeleton_stream_.get(); }
  // Sends the director's view (view 0), every blended image as it is made, live to `target`
  // (VideoFeed: H.264 in MPEG-TS over UDP or SRT, at the view's size, scaled to it should the
  // view change), beside a recording if one is under way; replaces a feed under way. Never waits
  // on the network: pictures the feed cannot take are dropped and counted. A feed that fails (the
  // connection refused or lost) stops, not the pipeline, and its one line is given to `stopped`
  // once, on the pipeline's thread.
  void feedView(const FeedTarget& target, std::function<void(const std::string&)> stopped = {});
  // Ends the feed and hands back its closed VideoFeed (frames sent, dropped, its error); none when
  // none was made.
  std::unique_ptr<VideoFeed> stopFeedingView();
  const VideoFeed* viewFeed() const { return view_feed_.get(); }
  // Ends the recording and hands back its closed recorder (file, frames, size, rate); none when
  // none was made.
  std::unique_ptr<ViewRecorder> stopRecordingView();
  // The recording under way (none when none is, or after it failed).
  const ViewRecorder* viewRecording() const {
    return view_recorder_failed_ ? nullptr : view_recorder_.get();
  }
  // Whether a recording stopped on a failure and was not ended yet.
  bool viewRecordingFailed() const { return view_recorder_ && view_recorder_failed_; }
  StudioCoordinator& studio() { return *studio_; }
  // The body mesh the studio and its nodes pose (options' coordinator.body, or the generic human
  // of options' body).
  const SkinnedMesh& body() const { return *options_.coordinator.body; }
  const Rig& rig() const { return rig_; }
  const std::vector<std::string>& nodeNames() const { return names_; }

 private:
  LocalRunOptions options_;
  std::unique_ptr<ViewRecorder> view_recorder_;
  std::unique_ptr<VmcSender> skeleton_stream_;
  bool view_recorder_failed_ = false;
  std::function<void(const std::string&)> view_recorder_stopped_;
  std::filesystem::path view_recorder_file_;
  std::unique_ptr<VideoFeed> view_feed_;
  std::function<void(const std::string&)> view_feed_stopped_;
  bool view_feed_told_ = false;  // its failure given to view_feed_stopped_
  // Hands view 0's blended images to the recording and the feed, whichever are under way.
  void sinkBlendedViews();
  void recordImage(const BlendedImage& image);
  void feedImage(const BlendedImage& image);
  Rig rig_;
  std::vector<std::string> names_;
  std::filesystem::path keys_;
  bool temporary_keys_ = false;
  std::unique_ptr<StudioCoordinator> studio_;
  std::vector<pid_t> children_;
  std::vector<bool> running_;
  std::vector<pid_t> killed_;  // by killNode, not yet reaped
  std::vector<std::string> exits_;
  int nodes_failed_ = 0;
  double frame_rate_ = 30;
};

}  // namespace lumistage
