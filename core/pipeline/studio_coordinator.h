#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "core/geometry/stage_volume.h"
#include "core/net/transport.h"
#include "core/pipeline/bounded_queue.h"
#include "core/pipeline/pipeline.h"
#include "core/pipeline/wakeup.h"
#include "core/refine/mesh_refiner.h"
#include "core/refine/refinement_statistics.h"
#include "core/render/partial_image_blender.h"
#include "core/render/vertex_visibility.h"
#include "core/tracking/pose_tracker.h"
#include "core/tracking/visual_hull_locator.h"

namespace lumistage {

struct StudioCoordinatorOptions {
  int silhouette_step = 4;
  // A node that has not answered a frame's stage this long after the first node did is left out
  // of that frame (fewer cameras, not a stall).
  std::chrono::milliseconds deadline{120};
  std::chrono::milliseconds lost_after{1000};  // no message for this long: the node is lost
  // A frame without an awaited node's image of a view (it missed the deadline) is shown only when
  // no whole frame was for this long: it lacks what only that node's cameras saw.
  std::chrono::milliseconds hold_incomplete{500};
  // While a quarter or more of the recent frames lack a node's image (an overloaded node whose
  // answers come after `deadline` every frame: holes in the view), the statistics' and the images'
  // deadlines follow the nodes' answers: 1.25 times the slowest awaited node's 90th percentile of
  // its last 32 answers (late ones too), never below `deadline` nor above this, until the nodes
  // answer within `deadline` again. Otherwise they are `deadline`: a node now and then late costs
  // no latency. (The 75th percentile, left as soon as the frames were whole again, still lost a
  // node's answers in a third of the frames of an overloaded machine, each frame's other nodes'
  // work with them: docs/lumigraph.md.)
  std::chrono::milliseconds max_deadline{480};
  int64_t max_frames = 0;  // stop after this many complete frames; 0: never
  // A frame begins (motion capture) only while fewer frames than this are between motion capture
  // and done; otherwise it is dropped before any work, so that a pipeline slower than its cameras
  // drops frames instead of queueing them (latency stays bounded). 0: no limit.
  int max_frames_in_flight = 3;
  // The largest view (width x height) the nodes will be asked to render, the default 320x240 at
  // least: what the largest message a node may send follows from, with the rig, and so the most a
  // connection may make the studio buffer. A larger view is refused (setView). The default covers
  // the studio window's viewport (1920 wide, up to 1.5 times as high).
  int64_t max_view_pixels = 1920 * 2880;
  int raw_bytes_per_pixel = 1;  // of the cameras' images (Bayer, mono: 1; RGB: 3)
  RefineConfig refine;          // the refinement module's parameters
  // The body mesh the nodes pose (the generic human). Its triangles give the refinement's
  // smoothness between neighbours; posed and refined here too, it gives which cameras see each
  // vertex (VertexVisibility, as the nodes' renderers compute it), sent with the offsets so that
  // no node renders the rig's depth maps: once a frame instead of once a node. Null: neither.
  std::shared_ptr<const SkinnedMesh> body;
};

// A camera's health as its node reports it in heartbeats.
struct CameraHealth {
  std::string camera;
  int64_t frames = 0, dropped = 0;
  double frame_rate_hz = 0;
  std::string last_error;
  std::string key = {};  // how its frames are keyed, in words (kKeyedFromMasks...); empty: unknown
};

struct NodeReport {
  std::string name;
  std::vector<CameraHealth> cameras;  // from the latest heartbeat
  bool lost = true;                   // now
  int64_t messages = 0, bytes = 0;
  int64_t frames_missed = 0;  // frames it was left out of
  int64_t times_lost = 0;     // how often it was marked lost (and came back, or not)
  int64_t bad_messages = 0;
  double silent_ms = -1;  // since its last message, when reported; < 0: never heard from
  // How long it takes to answer, medians of recent frames on the studio's clock (< 0: none yet):
  // the pose sent to its statistics here, the offsets sent to its image here. A node slower than
  // the others (an overloaded PC, a slow link) shows here before it misses deadlines.
  double statistics_ms = -1, image_ms = -1;
  // What it sent for a frame shown (silhouettes, statistics, images), mean over those frames; -1
  // before the first.
  double bytes_per_frame = -1;
  TakeStatusData take;  // its recording of the take, from the latest heartbeat
  // How long its takes' disk (take.free_bytes) lasts recording its cameras at the rate they
  // deliver, raw, as takes are written; -1: unknown (no free space or no rate reported yet).
  double take_seconds_left = -1;
};

// The pipeline's output for a frame: the nodes' partial images normalised and blended.
struct BlendedImage {
  int64_t frame_id = -1;
  int width = 0, height = 0;
  // Premultiplied: alpha 255 where a camera contributed, the silhouette's feather (alpha < 255,
  // featherSilhouette) beside it, 0 elsewhere.
  std::vector<uint8_t> rgba;
  PoseData pose;  // the pose the nodes rendered it with (its frame's, not the newest)
};

// When a frame was done, from the first counted frame, and its latency (for plots).
struct FrameTiming {
  double done_s = 0;
  double latency_ms = 0;
};

// What `lumistage run` prints and writes as JSON.
struct RunReport {
  double fps = 0;         // frames shown a second since the first (the run's rate)
  double fps_recent = 0;  // the same over the last kRecentFrames shown (the rate now)
  static constexpr size_t kRecentFrames = 60;
  double latency_ms_p50 = 0, latency_ms_p95 = 0;  // node capture to frame done
  std::map<std::string, double> stage_ms;         // mean per stage
  // Where a shown frame's latency went, mean ms, in the frame's order (kLatencyParts): to_studio
  // (capture, keying and the network to the studio's first silhouettes), silhouettes (waiting for
  // the last node's), mocap_queued (for the tracker), mocap (the fit), pose_out (the pose to the
  // nodes), statistics (the nodes' sampling, its queue and the network), refine (with the
  // visibility), images (the nodes' rendering, its queue and the network) and blend. They add up
  // to the mean latency: the first is the rest of it (the nodes' clocks against the studio's).
  std::vector<std::pair<std::string, double>> latency_parts_ms;
  // What a node sends for a frame shown (its silhouettes, statistics and images), mean over the
  // nodes and frames; and what it sends a second, everything, mean over the nodes.
  double node_bytes_per_frame = 0, node_bytes_per_s = 0;
  double raw_bytes_per_frame_per_node = 0;  // what the node's cameras deliver
  int64_t frames = 0;                       // done: blended and shown
  int64_t frames_dropped = 0;  // never shown: refused, overtaken, or reached by no node's image
  int64_t frames_refused =
      0;  // of the dropped: at admission, before any work (max_frames_in_flight)
  // Of the dropped, after admission: overtaken (pushed out of the tracker's queue by a newer frame,
  // still open when a newer one was shown, or in flight when the cameras' frame ids moved), or
  // finished unshown (no node's image reached it, or held back: frames_held). Every dropped frame
  // is refused, overtaken or unshown.
  int64_t frames_overtaken = 0, frames_unshown = 0;
  // Shown without some awaited node's image (no whole frame for hold_incomplete); and, of the
  // dropped, held back for that.
  int64_t frames_incomplete = 0, frames_held = 0;
  int peak_frames_begun = 0;  // the most frames between motion capture and done at once
  // The statistics' and the images' deadlines now (ms): StudioCoordinatorOptions::deadline, or
  // longer while they follow a late node's answers (deadlines_following; max_deadline).
  double statistics_deadline_ms = 0, image_deadline_ms = 0;
  bool deadlines_following = false;
  double hull_agreement = 0;  // share of posed vertices seen inside the silhouettes
  // Of the frames done, those whose pose the tracker gave (the others: nobody tracked, the generic
  // human placed where the hull is, in its rest pose).
  int64_t frames_tracked = 0;
  std::vector<NodeReport> nodes;
  // Connections turned away: keys refused and handshakes that failed (StudioEndpoint).
  int64_t refusals = 0;
  std::vector<FrameTiming> timeline;  // every counted frame, up to kTimelineFrames
  int frames_in_flight = 0;           // frames begun and not yet done or given up
};

// The node whose takes' disk holds the least recording time (NodeReport::take_seconds_left), of
// those streaming that have said (a lost node's figure is stale); nullptr when none has.
const NodeReport* fullestTakeDisk(const RunReport& report);

// The studio's side of the distributed pipeline (DESIGN.md §1), one frame at a time per stage but
// several frames in flight: silhouettes of frame f from the nodes -> the motion capture module
// places the body -> pose(f) to the nodes -> their per-vertex statistics -> the module combines
// them exactly -> the refinement's offsets to the nodes -> their partial lumigraph images of every
// view -> blended. Motion capture is the PoseTracker (the visual-hull locator places the generic
// human while nobody is tracked), on a thread of its own: the other stages, the nodes' messages
// and the deadlines go on while it fits a frame. At most max_frames_in_flight frames are in or
// past motion capture at once: a newer frame is dropped on arrival, so that latency stays
// bounded. Never blocks
// on one node: each stage waits for the nodes at most `deadline`; a silent node is marked lost
// and rejoins by itself when it speaks again.
class StudioCoordinator {
 public:
  StudioCoordinator(const Rig& rig, StudioEndpointConfig endpoint, int body_joint_count,
                    StudioCoordinatorOptions options = {});
  ~StudioCoordinator();
  StudioCoordinator(const StudioCoordinator&) = delete;
  StudioCoordinator& operator=(const StudioCoordinator&) = delete;

  std::string endpoint() const { return endpoint_.endpoint(); }
  // The largest message the endpoint takes (from the rig and max_view_pixels).
  size_t maxMessageBytes() const { return endpoint_.maxMessageBytes(); }
  // Runs until `stop`, or `max_frames` frames are done.
  void run(const std::atomic<bool>& stop);
  // Handles what arrives within `duration` (or until `max_frames` are done), then returns: the
  // same work as run(), in slices, so a caller on one thread can look at the state between them.
  void runFor(std::chrono::milliseconds duration);
  int64_t framesDone() const { return frames_done_; }
  // Another limit for run(), runFor() and the frames counted; 0: none. While a limit holds, the
  // frames shown beyond it are not counted: report() taken then gives the frames asked for.
  void setMaxFrames(int64_t frames) { options_.max_frames = frames; }
  RunReport report() const;
  // The virtual cameras the nodes render for, each a stream of blended images (default: view 0,
  // the stage from the front-left). setView replaces the view of the same id or adds it; a view
  // larger than max_view_pixels is refused (logged; the views stay as they were).
  void setView(const ViewData& view);
  void setViews(std::vector<ViewData> views);
  void removeView(int view);
  const std::vector<ViewData>& views() const { return views_; }
  const ViewData& view() const { return views_.front(); }
  const Rig& rig() const { return rig_; }
  // The newest blended image of a view (empty before its first frame).
  const BlendedImage& lastImage(int view = 0) const;
  // Called with every blended image of every view as it is made (a ViewRecorder records them);
  // an empty function stops it.
  void setBlendedSink(std::function<void(int view, const BlendedImage&)> sink) {
    blended_sink_ = std::move(sink);
  }
  // Called once for every frame shown (after its blended images), with the pose its images were
  // rendered with and whether the tracker found the actor in it (else: the generic human at rest
  // where the hull is, or the tracker's first frames): what a live feed of the skeleton sends
  // (VmcSender), on this thread, so it must not block. An empty function stops it.
  void setShownPoseSink(
      std::function<void(int64_t frame_id, const PoseData& pose, bool tracked)> sink) {
    shown_pose_sink_ = std::move(sink);
  }
  // The body pose the motion capture module sent the nodes last (for overlays); its frame id.
  const PoseData& lastPose() const { return last_pose_; }
  int64_t lastPoseFrame() const { return last_pose_frame_; }
  // The silhouettes the nodes keyed for frame `frame_id` (one a camera that sent its own;
  // LowResSilhouette::camera says which), kept for the last kKeptSilhouettes frames motion capture
  // fitted; null for another. What the technician's silhouette overlay shows over the frame's
  // picture, however the nodes key (green, a clean plate, a session's masks).
  static constexpr int kKeptSilhouettes = 8;
  const std::vector<LowResSilhouette>* silhouettesOf(int64_t frame_id) const;
  // "streaming", "lost" or "unknown" (never heard from).
  std::string nodeState(const std::string& node) const;

  // Takes: every node records its own cameras' frames on its own disk (TakeRecorder), the same
  // frame ids on every node, from a frame kTakeLeadFrames ahead of the newest the studio has seen
  // (the command reaches every node before its cameras get there). A node that misses the
  // command, or comes back during the take, is told again at its next heartbeat; a node still
  // recording a take this studio did not ask for (it restarted mid-take) is told to stop. Fails
  // saying why the take cannot start (a bad name, one already recording, the name of the last
  // take).
  Status startTake(const std::string& take);
  // Ends the take kTakeLeadFrames frames ahead of the newest seen, the same on every node; the
  // nodes close their parts when their cameras pass it (a node already past it when the stop
  // arrives, behind a studio that lags, closes at once; the merge keeps the frames every node
  // holds). Nothing when no take is recording.
  void stopTake();
  // The take asked for (its name empty before the first), and whether it is still recording.
  const RecordData& take() const { return take_; }
  bool recordingTake() const {
    return !take_.take.empty() && take_.last_frame == RecordData{}.last_frame;
  }
  // A second at 30 fps: enough for the command to reach every node before its cameras get there,
  // even from a studio that sees the frames late (a loaded PC; in the tests, 15 was not).
  static constexpr int64_t kTakeLeadFrames = 30;

 private:
  struct FrameState {
    int64_t first_ns = 0;     // steady clock, when the first node's silhouettes arrived
    int64_t admitted_ns = 0;  // handed to the tracker's queue
    int64_t mocap_start_ns = 0, mocap_end_ns = 0;  // the fit
    int64_t captured_ns = 0;  // the earliest node capture time (wall clock: wallNowNs)
    std::vector<LowResSilhouette> silhouettes;
    // The actor's colours in each of those cameras, as sent (SilhouetteMaskData::colours): empty
    // on most frames; laid on the cells' grid only when the tracker asks for them.
    std::vector<std::vector<uint8_t>> colours;
    std::set<std::string> silhouette_nodes, pose_nodes, statistics_nodes;
    bool mocap_begun = false;  // handed to the motion capture thread
    int64_t pose_sent_ns = 0;
    PoseData pose;                    // sent to the nodes
    bool tracked = false;             // the pose is the tracker's (not the placed generic human)
    RefinementStatistics refine_sum;  // the nodes' statistics, combined exactly
    int64_t offsets_sent_ns = 0;      // the refinement began (its deadline counts from here)
    int64_t offsets_out_ns = 0;       // the offsets went out to the nodes
    std::map<int, std::set<std::string>> image_nodes;  // per view
    std::map<int, PartialImageBlender> blends;         // per view
    // The views sent with its pose (id, width, height): the nodes render it with those, and its
    // images are taken and waited for by them, not by a view changed or added since.
    std::vector<std::array<int, 3>> views;
    // Per node (NodeState::index), the bytes of its messages for it: silhouettes, statistics,
    // images.
    std::vector<int64_t> node_bytes;
    void addBytes(int node, size_t bytes) {
      if (node < 0) return;
      if (node_bytes.size() <= size_t(node)) node_bytes.resize(node + 1, 0);
      node_bytes[node] += int64_t(bytes);
    }

    // Empties it for another frame, keeping its buffers (the statistics' half a megabyte, a
    // blend's five at 640x480), which a fresh frame would allocate and fault in again.
    void clearForReuse();
  };
  struct NodeState {
    std::string peer;
    int64_t last_ns = 0;
    NodeReport report;
    RecentSamples statistics_ms{256}, image_ms{256};  // its answers' times
    bool told_silhouette_size = false;  // warned once that its silhouettes are of another step
    bool told_statistics = false;       // warned once that its statistics do not fit
    bool told_frame_id = false;         // warned that its frame ids are far from the others'
    int64_t newest_frame = -1;          // the frame id of its newest silhouettes
    int64_t heard_ns = 0;               // when it was first heard (again, after being lost)
    int64_t silhouettes_ns = 0;         // when its silhouettes were last used
    bool told_no_frames = false;        // warned that it is heard but sends no usable silhouettes
    // While counting: the bytes of its messages, and when its last came (steady clock).
    int64_t counted_bytes = 0, counted_to_ns = 0;
    // The frames shown that it sent something for, and the bytes it sent for them.
    int64_t shown_bytes = 0, shown_frames = 0;
    int index = -1;  // in the rig's nodes
    // Its ids refused since (0: accepted); when it was last told a shift, and the shift its last
    // refused silhouettes suggested (followLoneNode).
    int64_t refused_since_ns = 0, frame_ids_told_ns = 0, suggested_shift = 0;
    int agreeing = 0;    // refused silhouettes in a row that suggested the same shift, less one
    int times_told = 0;  // shifts told since its ids were last accepted
    int64_t lag_ns = 0;  // how long after an instant's first silhouettes its own come, smoothed
    // Its last answers' times (ms), late ones too: what the stages' deadlines follow.
    RecentSamples statistics_answers{32}, image_answers{32};
  };
  // Whether frames wait for the node: for its silhouettes, and for its answer to their poses. It is
  // heard, and other nodes' silhouettes have not been used for lost_after without its own (since
  // it was heard). A node that is heard but whose silhouettes are not used (its cameras
  // unplugged, its frame ids or its protocol another's) made every frame wait out two deadlines.
  bool awaited(const NodeState& node) const;
  int64_t newest_silhouettes_ns_ = 0;  // when any node's silhouettes were last used
  int64_t silhouettes_began_ns_ = 0;   // when they began to come, after none for lost_after
  // The cameras' frame ids move together, a frame at a time. A node's silhouettes whose frame id
  // lies more than kFrameIdWindow (message_codec.h) from the newest the studio has seen (a corrupt
  // or hostile message, a node replaying another session, cameras restarted on one node alone) are
  // refused and counted, instead of ending every frame in flight or leaving every later frame
  // "done" already; when most live nodes' ids move together (the cameras or the session restarted),
  // the studio follows them. False: refuse the message.
  bool acceptFrameId(NodeState& node, int64_t frame_id);
  // A node whose ids alone lie far from the others' while its silhouettes arrive in step with
  // theirs (its cameras restarted alone: a node's PC rebooted, its cameras power-cycled) is told
  // the shift that puts its ids on the others' count (FrameIdsData), once its silhouettes have
  // been refused for kFollowAfter and three in a row agree on the shift; told kTimesTold times
  // without its ids coming back, it is told no more. Instants are matched by when the silhouettes
  // reach the studio, on its own clock (the PCs' clocks may be off by whole frames), less the
  // node's usual lag behind the first node's: each frame's first arrival is kept for the last
  // kInstants ids. Only ids beyond the window the studio accepts (kFrameIdWindow) are refused and
  // so followed: cameras that keep counting on through a restart, or whose node's source counts
  // them on (AravisSource), are not.
  void followLoneNode(NodeState& node, int64_t frame_id);
  // The frame id whose silhouettes first arrived within a third of a frame period of `arrived_ns`
  // (steady clock), counting on from the recent frames at their rate; -1 when none does.
  int64_t idArrivingAt(int64_t arrived_ns) const;
  static constexpr int kInstants = 64;
  static constexpr std::chrono::seconds kFollowAfter{1};
  static constexpr int kAgreeing = 2, kTimesTold = 3;
  std::array<std::pair<int64_t, int64_t>, kInstants> instants_;  // (frame id, first arrival)

  // The frame's state, a spare one when it is new.
  FrameState& frameState(int64_t frame_id);
  // Removes the frame, keeping its state for another; returns the next frame.
  std::map<int64_t, FrameState>::iterator retireFrame(std::map<int64_t, FrameState>::iterator it);
  // A frame's motion capture, on the thread of its own (mocapLoop): its silhouettes in, its pose
  // out.
  struct MocapJob {
    int64_t frame_id = 0;
    std::vector<LowResSilhouette> silhouettes;
    std::vector<std::vector<uint8_t>> colours;  // FrameState::colours
    PoseData pose;
    bool tracked = false;  // the tracker found the actor (else: placed at rest)
    double ms = 0;         // how long the fit took
    int64_t start_ns = 0;  // when it began (steady clock)
  };
  void onMessage(const ReceivedMessage& received);
  // onMessage's parts: the node heard from (lost no longer, the traffic's count begun); its
  // heartbeat (its cameras' health, its take told again when it missed it); silhouettes' frame
  // accepted (false: refused) and the cameras' pace noted; an answer timed against the deadlines;
  // and each message of a frame: silhouettes (motion capture begins once every node's are in),
  // the refinement's statistics and a partial image (the frame finishes once every node's are).
  void noteHeard(NodeState& node, const ReceivedMessage& received);
  void onHeartbeat(NodeState& node, const HeartbeatData& heartbeat);
  bool noteSilhouettes(NodeState& node, const Message& message);
  void timeAnswer(NodeState& node, const Message& message);
  void onSilhouettes(NodeState& node, int64_t frame_id, int64_t sent_ns,
                     const SilhouettesData& silhouettes, size_t bytes);
  void onStatistics(NodeState& node, int64_t frame_id, const VertexStatisticsData& stats,
                    size_t bytes);
  void onImage(NodeState& node, int64_t frame_id, const PartialImageData& image, size_t bytes);
  // Admits the frame (max_frames_in_flight) and hands its silhouettes to the motion capture
  // thread.
  void beginMocap(int64_t frame_id, FrameState& frame);
  void mocapLoop();
  // The poses the motion capture thread made: each to the nodes, if its frame is still open.
  void takePoses();
  // The views and the frame's pose to every node.
  void sendPose(int64_t frame_id, FrameState& frame);
  bool acceptsView(const ViewData& view) const;
  // Whether the statistics are of the body's vertices (the nodes pose that body).
  bool bodyFits(int vertex_count) const {
    return options_.body && options_.body->rest.vertexCount() == vertex_count;
  }
  // The vertices that statistics of `vertex_count` points refine: the body's, when they hold its
  // vertices alone or with their window points (RefineConfig::window_points); without a body to
  // tell, the points of the window this studio's refinement is configured with.
  int refinedVertices(int vertex_count) const {
    constexpr int kWindow = RefineConfig::kWindowPoints;
    if (bodyFits(vertex_count)) return vertex_count;
    if (vertex_count % kWindow == 0 && bodyFits(vertex_count / kWindow))
      return vertex_count / kWindow;
    const int points = options_.refine.pointsPerVertex();
    return vertex_count % points == 0 ? vertex_count / points : vertex_count;
  }
  // The refinement module: chooses every vertex's offset from the combined statistics and sends
  // the offsets to the nodes, with which cameras see each vertex of the refined body.
  void runRefinement(int64_t frame_id, FrameState& frame);
  void finishFrame(int64_t frame_id, FrameState& frame);
  // A shown frame's latency (`latency_ms`, from its capture) split into its parts
  // (latency_parts_ms_), from its timestamps: `finish_ns` when it was finished, `now_ns` after it
  // was blended. A frame missing one (not refined) is left out.
  void addLatencyParts(const FrameState& frame, double latency_ms, int64_t finish_ns,
                       int64_t now_ns);
  void checkDeadlines(int64_t now_ns);
  // Reads what the nodes sent (waiting up to 10 ms for the first message or a pose), sends the
  // poses made meanwhile, then checks deadlines.
  void pump();
  void maybeFinish(int64_t frame_id, FrameState& frame);
  void sendTake(NodeState& node);

  Rig rig_;
  StudioEndpoint endpoint_;
  StudioCoordinatorOptions options_;
  StageChoice stage_;                     // the box the actor is looked for in
  VisualHullLocator locator_;             // places the generic human while nobody is tracked
  std::unique_ptr<PoseTracker> tracker_;  // the human skeleton's mocap (null for another body)
  // The motion capture module runs on a thread of its own (it alone uses locator_ and tracker_):
  // while it fits one frame (25 ms; a second for its first, which calibrates the body), this
  // thread goes on reading the nodes and refining and blending the frames ahead of it.
  // One frame waits for the tracker at most: a newer one pushes it out (the stage fell behind,
  // and a queue would only add latency). Closed to stop the thread.
  BoundedQueue<MocapJob> mocap_jobs_{1};
  BoundedQueue<MocapJob> mocap_done_{4};  // poses made; this thread takes them at every pump
  std::vector<MocapJob> spare_jobs_;      // this thread's, their buffers kept
  Wakeup mocap_ready_;                    // a pose is done
  std::thread mocap_thread_;  // started by the constructor's last line, joined by the destructor
  bool told_clocks_ = false;  // warned that a node's clock is far from the studio's
  std::string mocap_error_;   // the motion capture's last error, said once
  std::optional<Skeleton> generic_skeleton_;  // the nodes' generic human's (with tracker_)
  std::unique_ptr<MeshRefiner> refiner_;      // made for the first statistics' vertex count
  // The refined mesh of the frame being sent, and which cameras see its vertices (reused).
  Pose body_pose_;
  std::vector<Eigen::Affine3f> body_transforms_;
  Eigen::Matrix3Xf posed_positions_, posed_normals_, refined_positions_;
  VertexVisibility visibility_;
  Message offsets_message_;  // the offsets and masks of the frame being sent (reused)
  RefinementStatisticsCodec statistics_codec_;  // the nodes' statistics, decompressed here
  int joints_;
  std::map<int64_t, FrameState> frames_;
  // Frames done or given up, kept for the next ones (frameState, retireFrame).
  std::vector<std::map<int64_t, FrameState>::node_type> spare_frames_;
  std::map<std::string, NodeState> nodes_;
  MessageEncoder encoder_;
  // The views sent with each pose (sendPose): one encoder a view, kept with its message.
  std::vector<std::unique_ptr<MessageEncoder>> view_encoders_;
  std::vector<std::span<const uint8_t>> view_bytes_;
  Message view_message_;
  int64_t newest_done_ = -1;
  int64_t newest_seen_ = -1;  // the newest frame any node sent silhouettes of
  RecordData take_;
  // The latest frames dropped before motion capture (at admission, or overtaken waiting for it),
  // a ring: their late silhouettes are ignored.
  std::array<int64_t, 8> refused_{-1, -1, -1, -1, -1, -1, -1, -1};
  size_t next_refused_ = 0;
  int64_t start_ns_ = 0, last_done_ns_ = 0;
  static constexpr size_t kTimelineFrames = 1 << 16;
  std::vector<std::pair<int64_t, float>> timeline_;  // done (steady ns), latency (ms)
  // Per part of a shown frame's latency (RunReport::latency_parts_ms), in that order.
  static constexpr std::array<const char*, 9> kLatencyParts = {
      "to_studio",  "silhouettes", "mocap_queued", "mocap", "pose_out",
      "statistics", "refine",      "images",       "blend"};
  std::array<RecentSamples, kLatencyParts.size()> latency_parts_ms_;
  RecentSamples latencies_ms_, mocap_ms_, combine_ms_, statistics_wait_ms_, blend_ms_, refine_ms_,
      visibility_ms_;
  RecentSamples recent_done_ns_{RunReport::kRecentFrames};  // when the latest frames were shown
  std::vector<ViewData> views_;
  std::map<int, BlendedImage> last_images_;
  std::function<void(int, const BlendedImage&)> blended_sink_;
  std::function<void(int64_t, const PoseData&, bool)> shown_pose_sink_;
  std::vector<uint8_t> decoded_;  // a partial image, reused
  PoseData last_pose_;
  int64_t last_pose_frame_ = -1;
  // silhouettesOf's frames, a ring (frame id -1: none yet), their buffers reused.
  std::array<std::pair<int64_t, std::vector<LowResSilhouette>>, kKeptSilhouettes> kept_silhouettes_;
  int next_kept_silhouettes_ = 0;
  // The frames dropped, by cause (RunReport).
  int64_t frames_done_ = 0, frames_refused_ = 0, frames_overtaken_ = 0, frames_unshown_ = 0;
  int64_t frames_incomplete_ = 0, frames_held_ = 0;
  int64_t last_whole_ns_ = 0;  // when a frame with every awaited node's images was last shown
  // When recent frames' poses and offsets went out, kept past the frames: late answers are timed.
  struct SentAt {
    int64_t frame_id = -1, pose_ns = 0, offsets_ns = 0;
  };
  std::array<SentAt, 64> sent_at_{};
  SentAt& sentAt(int64_t frame_id) { return sent_at_[size_t(frame_id) % sent_at_.size()]; }
  // The stages' deadlines (steady ns), following the nodes' answers (max_deadline); updated as
  // frames finish.
  void updateDeadlines();
  int64_t statistics_deadline_ns_ = 0, image_deadline_ns_ = 0;
  double incomplete_share_ = 0;  // of the recent frames drawn, those without some node's image
  // Whether the deadlines are stretched past `deadline` to a late node's answers.
  bool deadlinesFollowing() const {
    const int64_t base = std::chrono::nanoseconds(options_.deadline).count();
    return statistics_deadline_ns_ > base || image_deadline_ns_ > base;
  }
  std::vector<double> quantile_scratch_;
  int64_t counting_since_ns_ = 0;  // when counting_ became true (steady clock)
  int peak_frames_begun_ = 0;
  // Figures count once every node has spoken (or a few seconds after the first did): a start-up
  // with nodes still loading is not the pipeline's speed.
  bool counting_ = false;
  int64_t first_message_ns_ = 0;
  double hull_agreement_sum_ = 0;
  int64_t frames_tracked_ = 0;  // counted frames whose pose the tracker gave
};

}  // namespace lumistage
