#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/body/skinned_mesh.h"
#include "core/capture/frame_source.h"
#include "core/imaging/cell_colours.h"
#include "core/imaging/keyer.h"
#include "core/imaging/silhouettes.h"
#include "core/net/transport.h"
#include "core/pipeline/bounded_queue.h"
#include "core/pipeline/take_recorder.h"
#include "core/pipeline/wakeup.h"
#include "core/refine/refinement_sampler.h"
#include "core/refine/refinement_statistics.h"
#include "core/render/egl_context.h"
#include "core/render/lumigraph_renderer.h"

namespace lumistage {

struct CameraNodeOptions {
  int silhouette_step = 4;
  // Every this many frames (by frame id) the silhouettes carry the actor's colours, three bytes a
  // cell of the actor (sampleSilhouetteColours): what motion capture places the arms by when it
  // finds the actor. 0: never.
  int colour_every = kColourEveryFrames;
  std::chrono::milliseconds heartbeat{250};
  int frames_kept = 8;  // frame sets kept for the statistics (poses arrive a few frames later)
  RefineConfig refine;  // the mesh refinement's parameters (offsets, depth maps, colour bits)
  // Where the node records the takes the studio asks for (<takes>/<take>/<node>/); empty: it
  // records none and says so when asked.
  std::filesystem::path takes;
  ImageFiles take_files = ImageFiles::kPnm;  // how takes store the images
  double fps = 25;                           // the cameras' frame rate, written with every take
  // An open take goes on while the studio is silent (a restart, a network outage) for at most
  // this long; then the node closes it, so that a studio that crashed for good does not fill the
  // node's disk.
  std::chrono::milliseconds unattended_take_limit{30'000};
  // A stage without a green screen, live: each camera's clean plate is learnt from the first
  // `plate_frames` whole sets, which must film the empty stage (the actor walks in after); those
  // sets show nobody. 0: none (cameras keyed on green, from a session's masks, or on its plate/).
  int plate_frames = 0;
};

// The node's part of every frame, on the PC that owns the cameras (see DESIGN.md §1):
// capture a set of its cameras' frames; key them at low resolution and send the silhouettes;
// when the studio's pose for that frame arrives, pose the generic human (linear blend skinning)
// and send, per vertex (and its window points) and offset along its normal, the refinement
// statistics of its cameras (RefinementSampler: outside-silhouette counts, colour counts, sums and
// squares, compact) — what the studio's refinement module combines exactly across nodes; when the
// studio's chosen offsets arrive, move the vertices and render the partial image of the refined
// mesh.
// Heartbeats carry every camera's counters. Takes the studio asks for are recorded on the node's
// own disk (TakeRecorder), from the capture thread's complete sets.
//
// Threads joined by drop-oldest bounded queues, so that capture, keying and statistics work on
// different frames at once and a slow stage loses old frames rather than delaying new ones:
//   capture -> [sets] -> silhouettes -> [outbox] -> network (this thread: sends, receives poses)
//   network -> [poses, offsets] -> statistics / partial images -> [outbox]
class CameraNode {
 public:
  CameraNode(const Rig& rig, const std::string& name, std::unique_ptr<FrameSource> source,
             NodeEndpointConfig endpoint, SkinnedMesh body, CameraNodeOptions options = {});

  // Runs until `stop` is set or the source ends.
  void run(const std::atomic<bool>& stop);
  // Why the source ended (after run() returned without `stop`): its failure, or that it ended.
  std::string sourceEnd();

  int64_t setsSent() const { return sets_sent_; }
  int64_t bytesSent() const { return bytes_sent_; }

  // What a monitor window on the node's PC shows: the latest frame set, its low-resolution
  // silhouettes (as sent) and the cameras' counters. Thread-safe; the frames are shared, not
  // copied.
  struct MonitorState {
    int64_t frame_id = -1;
    std::shared_ptr<const void> keep_alive;  // holds `frames`
    std::vector<const CameraFrame*> frames;  // per own camera
    std::vector<SilhouetteMaskData> silhouettes;
    std::vector<CameraStats> stats;  // per own camera
    int64_t sets_sent = 0, bytes_sent = 0;
    TakeStatusData take;  // the take the studio asked for, and how its recording goes
  };
  MonitorState monitorState();
  const std::vector<int>& cameras() const { return cameras_; }

 private:
  struct Set {
    int64_t frame_id = -1;
    int64_t captured_ns = 0;          // wall clock (wallNowNs)
    std::vector<CameraFrame> frames;  // per own camera; has(k) when camera k's frame is in it
    bool has(size_t k) const { return frames[k].frame_id == frame_id; }
    // Per own camera, the green-screen key of the refinement's samples and the renderer's masks
    // for this set, as learnt when it was captured (shared by every set since).
    std::shared_ptr<const std::vector<GreenScreenKeyer>> keyers;
    // Per own camera, its clean plate where it is keyed on one (null: on green or from masks), as
    // learnt when the set was captured; `empty_stage`: a set the plates are being learnt from,
    // whose cameras without a plate yet show nobody.
    std::shared_ptr<const CameraPlates> plates;
    bool empty_stage = false;
  };
  // Learns the own cameras' green screens from a set (the capture thread's, during warm-up).
  void learnScreens(const Set& set);
  // Camera frames whose image buffers wait for the next frames: a set's frames come back when
  // the last holder of the set lets it go (the queues, kept_, posed_, the monitor), so that in the
  // steady state the capture thread never allocates an image (a fresh 786 KB buffer a camera and
  // frame is zero-filled and faulted in page by page).
  class FramePool {
   public:
    void give(std::vector<CameraFrame>& frames);  // any thread
    // A spare frame's buffers into `frame`, when it has none and there is one.
    void take(CameraFrame& frame);

   private:
    std::mutex mutex_;
    std::vector<CameraFrame> spare_;
  };
  // A new set whose frames go back to the pool when it is released.
  std::shared_ptr<Set> newSet();
  // The capture thread's sets on their way to the take, which records whole sets only, in
  // increasing ids: a whole set goes at once, unless one before it still waits; a set that went
  // out without a late camera's frame (its PC loaded, not the camera gone) waits for that frame up
  // to kLateFrames newer ids, and the sets after it wait behind it.
  class TakeBacklog {
   public:
    static constexpr int64_t kLateFrames = 30;
    TakeBacklog(TakeRecorder& takes, FramePool& pool, size_t cameras)
        : takes_(takes), pool_(pool), cameras_(cameras) {}
    // A set gone out: `whole`, or without cameras that are late only (`late_only`; one without a
    // silent camera cannot be recorded).
    void add(const std::shared_ptr<Set>& set, bool whole, bool late_only);
    // Own camera k's `frame`, when a waiting set went out without it: kept for the take, `frame`
    // given spare buffers, and true.
    bool catchLate(CameraFrame& frame, size_t k);
    // The waiting sets that are complete now, to the take in order; those still incomplete
    // kLateFrames behind `newest` (or any, `all`: the ids restart, the capture ends) are left out.
    void release(int64_t newest, bool all);

   private:
    struct Waiting {
      std::shared_ptr<Set> set;
      std::vector<CameraFrame> late;  // per own camera: its frame, come after the set went out
      bool complete() const;
    };
    // A set to the take: its own frames, and `late` ones (per own camera) where it has none.
    void offer(const Set& set, const std::vector<CameraFrame>& late);

    TakeRecorder& takes_;
    FramePool& pool_;
    const size_t cameras_;
    std::deque<Waiting> waiting_;
    std::vector<const CameraFrame*> frames_;  // a set's, reused
  };

  void captureLoop(const std::atomic<bool>& stop);
  // The capture thread's state from frame to frame (captureLoop's), and its steps.
  struct Capture;
  // The log lines when every camera has gone silent (no frame in `got`), and when frames come back.
  void tellAllSilent(Capture& capture, bool got, std::chrono::steady_clock::time_point now);
  // The studio's shift applied to capture.frame's id; the sets begin afresh on a new shift or when
  // the cameras restarted their count.
  void followIds(Capture& capture);
  // capture.frame, of own camera k, into its set; false when it was a late frame, kept for the
  // take.
  bool addFrame(Capture& capture, size_t k, std::chrono::steady_clock::time_point now);
  // The sets no longer waiting for a camera, sent out (and to the take).
  void sendWaitedSets(Capture& capture, std::chrono::steady_clock::time_point now);
  // The log lines for the cameras set `s` goes out without, and at most every kTellLateEvery the
  // late ones' tally; whether the cameras it goes out without are all late only.
  bool tellMissingCameras(Capture& capture, const Set& s,
                          std::chrono::steady_clock::time_point now);
  void silhouetteLoop(const std::atomic<bool>& stop);
  void statisticsLoop(const std::atomic<bool>& stop);
  Message silhouettesOf(const Set& set) const;
  std::optional<Message> statisticsFor(const Message& pose);
  // Applies the studio's offsets to that frame's posed mesh and renders its partial images.
  std::vector<Message> partialImagesWithOffsets(const Message& offsets);
  // The node's partial lumigraph images of the (refined) posed surface, one per desired view,
  // rendered with OpenGL (LumigraphRenderer, its own cameras' images): colour = the weighted
  // mean of its cameras, alpha = their share of the weight of all the rig's cameras on a log
  // scale (shareOfAlpha; the studio's normalisation weighs the nodes by it); alpha-run encoded.
  // Empty when no OpenGL context could be had (said once in the log). `visibility`: the studio's
  // masks of which cameras see each vertex (VertexVisibility), or empty: the renderer computes
  // them.
  std::vector<Message> partialImagesFor(const Set& set, int64_t frame_id,
                                        const std::vector<ViewData>& views,
                                        const Eigen::Vector3d& pivot,
                                        std::span<const CameraMask> visibility);
  bool send(Message message);
  // Queues a message for the main thread to send, and wakes it.
  void post(Message message);

  Rig rig_;
  std::string name_;
  std::string studio_address_;  // where the node connects to the studio, for its messages
  std::vector<int> cameras_;    // rig indices of this node's cameras
  std::unique_ptr<FrameSource> source_;
  std::mutex source_mutex_;  // next() on the capture thread, stats() on the network thread
  // The other threads waiting for source_mutex_ (lockSource), whom the capture thread lets in
  // first. It holds the mutex while next() waits for a frame (up to 5 ms) and takes it again
  // within nanoseconds of letting it go, so a waiter woken on another core found it taken again,
  // time after time: the network thread, which takes the cameras' health for every heartbeat
  // (4 a second), waited 22-29 ms on average and up to 150 ms, sending and reading nothing
  // meanwhile (`lumistage run`, reference rig, this 2-core machine); now 3-4 ms, at most 14.
  std::atomic<int> source_waiters_{0};
  // source_mutex_ for a thread other than the capture thread.
  std::unique_lock<std::mutex> lockSource();
  // Per own camera, what learning its green screen found wrong (empty: nothing); under
  // source_mutex_, written by the capture thread, sent in every heartbeat.
  std::vector<std::string> screen_warnings_;
  // Per own camera, 1 where its frames carry the actor's mask (FrameSource::hasMasks: a session
  // filmed without a green screen, segmented by another tool): its silhouettes, the refinement's
  // keying and the renderer's masks come from the masks, and no green screen is learnt for it.
  std::vector<uint8_t> masked_;
  // Per own camera, its clean plate (a stage without a green screen), learnt from the frames of
  // the empty stage its source filmed (FrameSource::plateImages: a session's plate/) when the node
  // is made, or from the first CameraNodeOptions::plate_frames sets (live): its silhouettes, the
  // refinement's keying and the renderer's masks are keyed on it, and no green screen is learnt for
  // it. The capture thread's; published_plates_ is the copy every set carries.
  CameraPlates plates_;
  std::shared_ptr<const CameraPlates> published_plates_;
  std::shared_ptr<const BackgroundModel> learnPlate(FrameSource& source, int camera) const;
  // Each own camera's key at start: from masks, on a plate its source filmed, on one to learn from
  // the first sets, or on green (camera_node_keys.cpp).
  void setUpKeys();
  // The plates being learnt from the first sets (the capture thread's), and the sets taken so far.
  std::vector<std::unique_ptr<BackgroundModel>> plates_learning_;
  int plate_sets_ = 0;
  void learnPlates(Set& set);
  bool learningPlate(size_t k) const { return plates_learning_.size() > k && plates_learning_[k]; }
  bool keyedOnGreen(size_t k) const { return !masked_[k] && !plates_[k] && !learningPlate(k); }
  // Per own camera, how it is keyed, in words (kKeyedOnGreen...), for the heartbeat: written by
  // the capture thread once a plate is learnt, read by the network thread.
  std::unique_ptr<std::atomic<const char*>[]> key_kinds_;
  // Whether own camera k's frame `frame` is keyed from its mask (one of the image's size).
  bool keyedFromMask(size_t k, const CameraFrame& frame) const {
    return masked_[k] && frame.mask.size() == size_t(frame.image.width) * frame.image.height;
  }
  NodeEndpoint endpoint_;  // the network thread's alone
  SkinnedMesh body_;       // the statistics thread's alone
  CameraNodeOptions options_;
  // The capture thread's alone: each own camera's green-screen key, learnt from the first set
  // whose screen keys cleanly, or else from each of the first kScreenWarmupSets sets (a camera
  // whose exposure is still settling), then kept (see kScreenRetrySets); published_keyers_ is the
  // copy every set carries, replaced only when learning changes the keys. The tracker's silhouettes
  // keep the fixed threshold its shape calibration was tuned with: keyed with the learnt one (0.1%
  // of the actor's pixels missed instead of 0.6%), the joints came closer on three clips of four
  // but the calibrated body sized the generic mesh worse (leave-one-out 1 to 2 dB lower). Every
  // kScreenRetrySets frames after that every camera's screen is measured again
  // (GreenScreenKeyer::follow): a camera whose screen could not be keyed then (a lens cap, the
  // lights still off) is learnt once it shows, its warning cleared; one whose lights dimmed or
  // brightened since is learnt again, and warned of when it is now too dim (0.09 ms of CPU a camera
  // at 1024x768, imaging_bench measureScreen, once a second at 30 fps).
  static constexpr int kScreenWarmupSets = 30, kScreenRetrySets = 30;
  void checkScreens(const Set& set);
  std::vector<GreenScreenKeyer> screen_measured_;  // each camera's previous measurement
  std::vector<GreenScreenKeyer> keyers_;
  std::shared_ptr<const std::vector<GreenScreenKeyer>> published_keyers_;
  int screen_sets_learnt_ = 0;  // sets learnt from so far; kScreenWarmupSets once fixed
  const GreenScreenKeyer silhouette_keyer_;
  std::shared_ptr<FramePool> frame_pool_ = std::make_shared<FramePool>();
  BoundedQueue<std::shared_ptr<const Set>> sets_{2};
  // The studio's poses and offsets, for the statistics thread (offsets first: they finish
  // frames), each queue dropping its oldest when the node falls behind; studio_work_ wakes the
  // thread when either gets one.
  BoundedQueue<Message> poses_{4};
  BoundedQueue<Message> offsets_{4};
  Wakeup studio_work_;
  BoundedQueue<Message> outbox_{32};
  Wakeup outbox_ready_;  // wakes the main thread, which sends the outbox, from its poll
  std::mutex view_mutex_;
  std::map<int, ViewData> views_;  // the latest of each desired view from the studio
  // The views the studio sent with each recent frame's pose (it sends every view it wants, just
  // before each pose): a frame is rendered with its own, not with the next frame's that came
  // while it was refined (the nodes' images of one frame, drawn from different views, blended
  // into doubled edges while a director dragged the view), and a view the studio stopped asking
  // for is rendered no more. Map nodes reused: no allocation once warm.
  struct FrameViews {
    std::vector<ViewData> views;  // the first `count` are the frame's; the rest keep their memory
    size_t count = 0;
  };
  std::map<int64_t, FrameViews> frame_views_;
  std::vector<std::map<int64_t, FrameViews>::node_type> spare_frame_views_;
  void keepView(int64_t frame_id, const ViewData& view);  // under view_mutex_
  std::vector<ViewData> render_views_;  // the frame's views, for the statistics thread
  // The statistics thread's alone: its OpenGL context and renderer (none when no context).
  std::unique_ptr<EglContext> gl_;
  std::unique_ptr<LumigraphRenderer> renderer_;
  std::vector<uint8_t> partial_rgba_;
  std::vector<Eigen::Affine3f> placements_;  // the actor and its clones in a view, reused
  LowResSilhouette mask_silhouette_;         // the renderer's foreground masks, reused
  std::vector<uint8_t> mask_;
  std::mutex kept_mutex_;
  std::map<int64_t, std::shared_ptr<const Set>> kept_;  // sets awaiting their pose
  std::atomic<bool> source_finished_{false};
  TakeRecorder takes_;
  MessageEncoder encoder_;
  Pose pose_;
  std::vector<Eigen::Affine3f> transforms_;
  Eigen::Matrix3Xf positions_, normals_;
  RefinementSampler sampler_;
  RefinementStatistics refine_stats_;
  RefinementStatisticsCodec statistics_codec_;  // compresses them for the wire
  std::vector<SamplerCamera> sampler_cameras_;
  std::vector<MaskKey> mask_keys_;  // per own camera, over the frame's mask (when keyed from it)
  std::vector<int> sampler_camera_index_;  // each sampler camera's index among the node's
  std::vector<uint8_t> told_sees_nobody_;  // said that the camera is left out (that thread's)
  struct Posed {
    std::shared_ptr<const Set> set;
    Eigen::Matrix3Xf positions, normals;
    Eigen::Vector3d pivot = Eigen::Vector3d::Zero();  // the actor's place on the floor, for clones
  };
  std::map<int64_t, Posed> posed_;  // frames awaiting their offsets (statistics thread's alone)
  bool told_offsets_ = false;       // said that the studio's offsets do not fit (that thread's)
  // The studio's latest offsets that fit the mesh, and their frame (statistics thread's): the
  // refinement's visibility in the frames after is that of the surface they make
  // (RefinementSampler::sample), while they are at most kSurfaceFrames ids away.
  std::vector<uint8_t> surface_levels_;
  int64_t surface_frame_ = -1;
  static constexpr int64_t kSurfaceFrames = 30;
  // Map nodes of frames done with, reused with their matrices: keeping a frame's posed mesh does
  // not allocate once warmed up.
  std::vector<std::map<int64_t, Posed>::node_type> spare_posed_;
  Posed& keepPosed(int64_t frame_id);
  void releasePosedUpTo(int64_t frame_id);
  std::atomic<int64_t> sets_sent_{0}, bytes_sent_{0};
  // Added to its cameras' frame ids: the studio's FrameIds shifts, summed (network thread), read
  // by the capture thread. Live cameras only (FrameSource::idsCountInstants).
  std::atomic<int64_t> id_offset_{0};
  std::atomic<int64_t> newest_raw_id_{0};  // the newest frame's id as its camera gave it
  void followFrameIds(int64_t offset);
  std::mutex monitor_mutex_;
  std::shared_ptr<const Set> monitor_set_;
  std::vector<SilhouetteMaskData> monitor_silhouettes_;
};

}  // namespace lumistage
