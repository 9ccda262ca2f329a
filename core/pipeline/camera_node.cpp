#include "core/pipeline/camera_node.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <limits>
#include <thread>

#include "core/base/error.h"
#include "core/imaging/cell_colours.h"
#include "core/imaging/partial_image_codec.h"
#include "core/net/posed_body.h"
#include "core/pipeline/pipeline.h"
#include "core/refine/mesh_refiner.h"
#include "core/render/clone_set.h"
#include "core/render/frame_inputs.h"

namespace lumistage {

CameraNode::CameraNode(const Rig& rig, const std::string& name, std::unique_ptr<FrameSource> source,
                       NodeEndpointConfig endpoint, SkinnedMesh body, CameraNodeOptions options)
    : rig_(rig),
      name_(name),
      studio_address_(endpoint.connect),
      source_(std::move(source)),
      endpoint_(std::move(endpoint)),
      body_(std::move(body)),
      options_(options),
      takes_(options.takes, rig, name, options.fps, options.take_files),
      sampler_(options.refine) {
  const std::optional<int> node = rig_.findNode(name_);
  if (!node) throw Error("camera node: no node '" + name_ + "' in the rig");
  cameras_ = rig_.nodes()[*node].cameras;
  keyers_.resize(cameras_.size());
  screen_measured_.resize(cameras_.size());
  published_keyers_ = std::make_shared<const std::vector<GreenScreenKeyer>>(keyers_);
  screen_warnings_.resize(cameras_.size());
  setUpKeys();
}
Message CameraNode::silhouettesOf(const Set& set) const {
  SilhouettesData silhouettes;
  LowResSilhouette s;
  for (size_t k = 0; k < cameras_.size(); ++k) {
    if (!set.has(k)) continue;  // a camera that delivers nothing: the studio goes without it
    const CameraFrame& frame = set.frames[k];
    if (keyedFromMask(k, frame)) {
      maskSilhouette(frame.mask.data(), frame.image.width, frame.image.height, cameras_[k],
                     options_.silhouette_step, s);
    } else if (const BackgroundModel* plate = (*set.plates)[k].get()) {
      computeSilhouette(*plate, frame.image.view(), cameras_[k], options_.silhouette_step, s);
    } else if (set.empty_stage) {  // its plate still being learnt: nobody
      s.reset(cameras_[k], options_.silhouette_step, frame.image.width, frame.image.height);
    } else {
      computeSilhouette(silhouette_keyer_, frame.image.view(), cameras_[k],
                        options_.silhouette_step, s);
    }
    std::vector<uint8_t> colours;
    if (options_.colour_every > 0 && set.frame_id % options_.colour_every == 0 && !set.empty_stage)
      sampleSilhouetteColours(frame.image.view(), s, colours);
    silhouettes.masks.push_back(
        {s.camera, s.width, s.height, std::move(s.bits), std::move(colours)});
  }
  Message message;
  message.frame_id = set.frame_id;
  message.sent_ns = set.captured_ns;
  message.body = std::move(silhouettes);
  return message;
}

std::optional<Message> CameraNode::statisticsFor(const Message& message) {
  std::shared_ptr<const Set> set;
  {
    std::lock_guard lock(kept_mutex_);
    const auto it = kept_.find(message.frame_id);
    if (it == kept_.end()) return std::nullopt;  // too old: dropped already
    set = it->second;
  }
  const PoseData& pose_data = std::get<PoseData>(message.body);
  posedBodyMesh(body_, pose_data, pose_, transforms_, positions_, normals_);

  // The refinement's samples: every vertex's offsets along its normal in this node's cameras.
  sampler_cameras_.clear();
  sampler_camera_index_.clear();
  for (size_t k = 0; k < cameras_.size(); ++k) {
    if (!set->has(k)) continue;
    const CameraFrame& frame = set->frames[k];
    SamplerCamera camera{&rig_.camera(cameras_[k]), frame.image.view(), &(*set->keyers)[k]};
    if (keyedFromMask(k, frame)) {
      mask_keys_[k] = MaskKey(frame.mask.data(), frame.image.width, frame.image.height,
                              isBayer(frame.image.format));
      camera.green_screen = nullptr;
      camera.mask = &mask_keys_[k];
    } else if ((*set->plates)[k]) {
      camera.green_screen = nullptr;
      camera.background = (*set->plates)[k].get();
    }
    sampler_cameras_.push_back(camera);
    sampler_camera_index_.push_back(static_cast<int>(k));
  }
  // Seen through the surface the studio refined an earlier frame to, if a recent one (the frames
  // in flight: usually one to three before this).
  const bool surface = surface_frame_ >= 0 && message.frame_id >= surface_frame_ &&
                       message.frame_id - surface_frame_ <= kSurfaceFrames;
  sampler_.sample(sampler_cameras_, positions_, normals_, body_.rest.triangles, refine_stats_,
                  surface ? std::span<const uint8_t>(surface_levels_) : std::span<const uint8_t>());
  told_sees_nobody_.resize(cameras_.size());
  for (size_t i = 0; i < sampler_cameras_.size(); ++i) {
    const int k = sampler_camera_index_[i];
    const uint8_t nobody = sampler_.seesNobody()[i];
    if (nobody == told_sees_nobody_[k]) continue;
    told_sees_nobody_[k] = nobody;
    const std::string& camera = rig_.camera(cameras_[k]).name();
    if (nobody) {
      spdlog::warn(
          "node {}: camera {}: sees nobody where the actor is tracked (moved, or its key "
          "broken?): left out of the refinement",
          name_, camera);
    } else {
      spdlog::info("node {}: camera {}: sees the actor again", name_, camera);
    }
  }
  VertexStatisticsData stats;
  stats.vertex_count = static_cast<uint32_t>(refine_stats_.vertex_count);  // with window points
  stats.offset_count = options_.refine.offset_count;
  statistics_codec_.encode(refine_stats_, stats.packed);
  // Kept until the studio's offsets for the frame arrive.
  if (!posed_.empty() && message.frame_id < posed_.rbegin()->first - kFrameIdWindow)
    releasePosedUpTo(posed_.rbegin()->first);  // the cameras restarted: as kept_
  Posed& posed = keepPosed(message.frame_id);
  posed.set = set;
  posed.positions = positions_;
  posed.normals = normals_;
  posed.pivot = Eigen::Vector3d(positions_.row(0).mean(), positions_.row(1).mean(), 0);
  while (static_cast<int>(posed_.size()) > options_.frames_kept)
    releasePosedUpTo(posed_.begin()->first);
  Message reply;
  reply.frame_id = message.frame_id;
  reply.sent_ns = steadyNowNs();
  reply.body = std::move(stats);
  return reply;
}

std::vector<Message> CameraNode::partialImagesFor(const Set& set, int64_t frame_id,
                                                  const std::vector<ViewData>& views,
                                                  const Eigen::Vector3d& pivot,
                                                  std::span<const CameraMask> visibility) {
  std::vector<Message> messages;
  if (!renderer_ || views.empty()) return messages;
  // Which cameras see each vertex: the studio's, computed once for every node, or (none from an
  // older studio) this node's own (the rig's depth maps, about 2 ms).
  renderer_->setMesh(positions_, normals_, body_.rest.triangles, visibility);
  for (size_t k = 0; k < cameras_.size(); ++k) {
    if (!set.has(k)) {
      // No frame of this camera in the set: its weight is taken away everywhere (the others,
      // and the other nodes', colour the view).
      const Camera& camera = rig_.camera(cameras_[k]);
      const int w = camera.width() / kMaskStep, h = camera.height() / kMaskStep;
      mask_.assign(size_t(w) * h, 0);
      renderer_->setMask(static_cast<int>(k), mask_, w, h);
      continue;
    }
    const ImageView image = set.frames[k].image.view();
    renderer_->setImage(static_cast<int>(k), image);
    // Where the mesh reaches beyond the actor in this camera, its colour is the screen's: the
    // camera's silhouette in 4-pixel cells (49,000 pixels keyed, 0.07 ms) masks it out, or the
    // frame's mask in those cells.
    if (keyedFromMask(k, set.frames[k])) {
      setForegroundMask(*renderer_, static_cast<int>(k), set.frames[k].mask, image.width,
                        image.height, mask_silhouette_, mask_);
    } else if ((*set.plates)[k]) {
      setForegroundMask(*renderer_, static_cast<int>(k), *(*set.plates)[k], image, mask_silhouette_,
                        mask_);
    } else {
      setForegroundMask(*renderer_, static_cast<int>(k), (*set.keyers)[k], image, mask_silhouette_,
                        mask_);
    }
  }
  for (const ViewData& view : views) {
    if (view.width <= 0 || view.height <= 0 || view.rotation.size() != 9 ||
        view.translation.size() != 3)
      continue;
    Eigen::Matrix3d R;
    for (int i = 0; i < 9; ++i) R(i / 3, i % 3) = view.rotation[i];
    R = Eigen::Quaterniond(R).normalized().toRotationMatrix();  // exact rotation from floats
    const Camera desired(
        "view", view.width, view.height, {view.fx, view.fy, view.cx, view.cy, 0}, {}, R,
        Eigen::Vector3d(view.translation[0], view.translation[1], view.translation[2]));
    // The actor where it was filmed, then its clones (turned about its place, shifted).
    placements_.assign(1, Eigen::Affine3f::Identity());
    for (size_t k = 0; k + 2 < view.clones.size(); k += 3) {
      Clone clone;
      clone.offset_m = Eigen::Vector2d(view.clones[k], view.clones[k + 1]);
      clone.yaw_rad = view.clones[k + 2];
      placements_.push_back(clone.transform(pivot).cast<float>());
    }
    renderer_->render(desired, placements_, partial_rgba_);
    PartialImageData image;
    image.view = view.view;
    image.width = view.width;
    image.height = view.height;
    image.encoding = ImageEncoding::kAlphaRuns;
    encodeAlphaRuns(partial_rgba_, image.data);
    Message message;
    message.frame_id = frame_id;
    message.sent_ns = steadyNowNs();
    message.body = std::move(image);
    messages.push_back(std::move(message));
  }
  return messages;
}

// Frames arrive camera by camera; a set goes out when every own camera that delivers is in. A
// camera that has delivered none of the node's last kSilentFrames sets (unplugged, its cable
// pulled, its port dead, or only late) no longer holds its node's sets back: they go out with
// the cameras there are, and the node says so. (Waiting for it lost the node's other cameras
// too: every set was incomplete and dropped.)
// A camera not heard from yet is waited for during the first kStartFrames frame ids.
// (kSilentFrames: the 4 sets the node waited on before.)
struct CameraNode::Capture {
  static constexpr int64_t kSilentFrames = 4, kStartFrames = 60;
  // A camera whose frames come more than kSilentFrames late (a loaded PC) rather than not at all:
  // the sets went out without it, and the take waits for its frames (TakeBacklog). It is said to
  // deliver nothing only after kTellSilentAfter without a frame; lateness is said at most every
  // kTellLateEvery.
  static constexpr auto kTellSilentAfter = std::chrono::seconds(1),
                        kTellLateEvery = std::chrono::seconds(10);
  // Every camera silent (no set goes out, so the per-camera warning never comes): said once
  // after kAllSilent, and again when frames come back.
  static constexpr auto kAllSilent = std::chrono::seconds(2);

  Capture(TakeRecorder& takes, FramePool& pool, size_t cameras)
      : last_id(cameras, -1),
        told_silent(cameras, 0),
        live(cameras, 0),
        for_take(takes, pool, cameras),
        delivered(cameras),
        sets_without(cameras, 0) {}

  std::map<int64_t, std::shared_ptr<Set>> assembling;
  std::vector<int64_t> last_id;
  std::vector<uint8_t> told_silent, live;
  TakeBacklog for_take;
  std::vector<std::chrono::steady_clock::time_point> delivered;
  std::vector<int64_t> sets_without;
  std::chrono::steady_clock::time_point told_late_at =
      std::chrono::steady_clock::now();  // counted since
  int64_t newest = -1, first = -1, applied_offset = 0;
  // The newest kSilentFrames + 1 ids seen, a ring (recent_count of them in all).
  std::array<int64_t, kSilentFrames + 1> recent_ids{};
  int64_t recent_count = 0;
  CameraFrame frame;
  std::chrono::steady_clock::time_point last_frame_at = std::chrono::steady_clock::now();
  bool told_all_silent = false;
};

void CameraNode::captureLoop(const std::atomic<bool>& stop) {
  Capture capture(takes_, *frame_pool_, cameras_.size());
  while (!stop) {
    bool got = false;
    {
      // The heartbeat's camera health (lockSource) goes first.
      while (source_waiters_.load(std::memory_order_acquire) > 0) std::this_thread::yield();
      std::lock_guard lock(source_mutex_);
      if (source_->finished()) break;
      got = source_->next(capture.frame, std::chrono::milliseconds(5));
    }
    const auto now = std::chrono::steady_clock::now();
    tellAllSilent(capture, got, now);
    if (!got) continue;
    const auto k =
        std::find(cameras_.begin(), cameras_.end(), capture.frame.camera) - cameras_.begin();
    if (k >= static_cast<long>(cameras_.size())) continue;
    followIds(capture);
    if (!addFrame(capture, size_t(k), now)) continue;
    sendWaitedSets(capture, now);
    // A camera fell behind.
    while (capture.assembling.size() > 4) capture.assembling.erase(capture.assembling.begin());
    capture.for_take.release(capture.newest, false);  // those that waited long enough
  }
  capture.for_take.release(capture.newest, true);
  source_finished_ = true;
}

void CameraNode::tellAllSilent(Capture& capture, bool got,
                               std::chrono::steady_clock::time_point now) {
  if (!got) {
    if (!capture.told_all_silent && now - capture.last_frame_at > Capture::kAllSilent) {
      capture.told_all_silent = true;
      spdlog::warn(
          "node {}: none of its {} cameras has delivered a frame for {} s (powered? "
          "cabled? acquisition stopped?)",
          name_, cameras_.size(),
          std::chrono::duration_cast<std::chrono::seconds>(now - capture.last_frame_at).count());
    }
    return;
  }
  capture.last_frame_at = now;
  if (capture.told_all_silent) {
    capture.told_all_silent = false;
    spdlog::info("node {}: frames again", name_);
  }
}

void CameraNode::followIds(Capture& capture) {
  CameraFrame& frame = capture.frame;
  // The studio's shift, when its cameras count other ids than the other nodes' (followFrameIds):
  // from the frame it is first seen on, sets begin afresh, as after a restart.
  newest_raw_id_ = frame.frame_id;
  if (capture.applied_offset != 0 && frame.frame_id + capture.applied_offset < 0) {
    // Its cameras counted from near 0 again under a shift back: the shift no longer holds
    // (the studio tells it another if need be).
    spdlog::warn("node {}: its cameras restarted their count: its ids no longer moved by {}", name_,
                 capture.applied_offset);
    int64_t expected = capture.applied_offset;
    id_offset_.compare_exchange_strong(expected, 0);
  }
  if (const int64_t shift = id_offset_; shift != capture.applied_offset) {
    capture.applied_offset = shift;
    capture.first = -1;
  }
  frame.frame_id += capture.applied_offset;
  // First, or cameras restarted.
  if (capture.first < 0 || frame.frame_id < capture.newest - kFrameIdWindow) {
    capture.first = capture.newest = frame.frame_id;
    capture.recent_count = 0;
    capture.recent_ids[capture.recent_count++] = capture.newest;
    std::fill(capture.last_id.begin(), capture.last_id.end(), -1);
    capture.assembling.clear();  // the old ids' sets would outlast every new one (lowest go first)
    capture.for_take.release(capture.newest, true);
  }
}

bool CameraNode::addFrame(Capture& capture, size_t k, std::chrono::steady_clock::time_point now) {
  CameraFrame& frame = capture.frame;
  capture.delivered[k] = now;
  // The late frame of a set that went out without it: for the take. Late, not gone: counted as
  // delivered, so that a camera that is always last (a slower link) is awaited again once it
  // keeps up.
  if (const int64_t id = frame.frame_id; capture.for_take.catchLate(frame, k)) {
    capture.last_id[k] = std::max(capture.last_id[k], id);
    capture.for_take.release(capture.newest, false);
    return false;
  }
  std::shared_ptr<Set>& set = capture.assembling[frame.frame_id];
  if (!set) {
    set = newSet();
    set->frame_id = frame.frame_id;
    set->frames.resize(cameras_.size());
  }
  std::swap(set->frames[k], frame);
  frame_pool_->take(frame);  // buffers of a set let go, for the next frame
  capture.last_id[k] = std::max(capture.last_id[k], set->frame_id);
  if (set->frame_id > capture.newest) {
    capture.newest = set->frame_id;
    capture.recent_ids[capture.recent_count++ % capture.recent_ids.size()] = capture.newest;
  }
  return true;
}

void CameraNode::sendWaitedSets(Capture& capture, std::chrono::steady_clock::time_point now) {
  // Which cameras a set waits for: those that deliver (or are not heard from yet, at first).
  // Counted in the sets the node saw, not in ids: a loaded node that skips frames (a replay's
  // ticks, a camera queue that drops its oldest) sees ids jump by more than kSilentFrames, and
  // took its cameras after the first for silent at every jump: the sets went out with one
  // camera in three (the demo, with the studio's window on the same 2 cores).
  const int64_t oldest_recent =
      capture.recent_count >= int64_t(capture.recent_ids.size())
          ? capture.recent_ids[capture.recent_count % capture.recent_ids.size()]
          : std::numeric_limits<int64_t>::min();
  for (size_t c = 0; c < cameras_.size(); ++c) {
    capture.live[c] = capture.last_id[c] >= 0
                          ? capture.last_id[c] >= oldest_recent
                          : capture.newest - capture.first < Capture::kStartFrames;
  }
  for (auto it = capture.assembling.begin(); it != capture.assembling.end();) {
    Set& s = *it->second;
    size_t present = 0;
    bool waiting = false;
    for (size_t c = 0; c < cameras_.size(); ++c) {
      present += s.has(c);
      waiting = waiting || (!s.has(c) && capture.live[c]);
    }
    if (waiting) {
      ++it;
      continue;
    }
    const bool late_only = tellMissingCameras(capture, s, now);
    s.captured_ns = wallNowNs();  // the studio's latency counts from it, maybe on another PC
    const bool whole = present == cameras_.size();
    if (whole && plate_sets_ < options_.plate_frames) learnPlates(s);
    s.plates = published_plates_;
    if (whole && screen_sets_learnt_ < kScreenWarmupSets)  // screens are learnt from whole sets
      learnScreens(s);
    else if (whole && s.frame_id % kScreenRetrySets == 0)
      checkScreens(s);
    s.keyers = published_keyers_;
    capture.for_take.add(it->second, whole, late_only);
    sets_.push(it->second);
    it = capture.assembling.erase(it);
  }
}

bool CameraNode::tellMissingCameras(Capture& capture, const Set& s,
                                    std::chrono::steady_clock::time_point now) {
  // Without a camera: one that delivers nothing, or one whose frames come late.
  bool late_only = true;
  for (size_t c = 0; c < cameras_.size(); ++c) {
    if (s.has(c)) {
      if (capture.told_silent[c]) {
        capture.told_silent[c] = 0;
        spdlog::info("node {}: camera {} delivers again", name_, rig_.camera(cameras_[c]).name());
      }
      continue;
    }
    const bool silent =
        capture.last_id[c] < 0 || now - capture.delivered[c] > Capture::kTellSilentAfter;
    late_only = late_only && !silent;
    if (!silent) {
      ++capture.sets_without[c];
    } else if (!capture.told_silent[c]) {
      capture.told_silent[c] = 1;
      capture.sets_without[c] = 0;  // gone, not late
      spdlog::warn("node {}: camera {} delivers no frames: its node's sets go out without it",
                   name_, rig_.camera(cameras_[c]).name());
    }
  }
  std::vector<int64_t>& sets_without = capture.sets_without;
  if (now - capture.told_late_at > Capture::kTellLateEvery &&
      std::any_of(sets_without.begin(), sets_without.end(), [](int64_t n) { return n > 0; })) {
    capture.told_late_at = now;
    for (size_t c = 0; c < cameras_.size(); ++c) {
      if (sets_without[c] == 0) continue;
      spdlog::warn(
          "node {}: camera {}: {} set{} went out without its frames, which came after {} newer "
          "sets (a take being recorded still gets them); is the node's PC overloaded?",
          name_, rig_.camera(cameras_[c]).name(), sets_without[c], sets_without[c] == 1 ? "" : "s",
          Capture::kSilentFrames);
      sets_without[c] = 0;
    }
  }
  return late_only;
}

std::unique_lock<std::mutex> CameraNode::lockSource() {
  source_waiters_.fetch_add(1, std::memory_order_acq_rel);
  // Counted out once the mutex is held, or if taking it throws (the capture thread would wait for
  // this thread for ever).
  struct CountedOut {
    std::atomic<int>& waiters;
    ~CountedOut() { waiters.fetch_sub(1, std::memory_order_acq_rel); }
  } counted_out{source_waiters_};
  return std::unique_lock(source_mutex_);
}

void CameraNode::followFrameIds(int64_t offset) {
  {
    const std::unique_lock lock = lockSource();
    if (!source_->idsCountInstants()) {
      spdlog::warn(
          "node {}: the studio finds its frame ids {} off the other nodes' for the same instants; "
          "its source's ids name its frames (a recording, the virtual studio): not moved (do the "
          "nodes replay one session?)",
          name_, offset);
      return;
    }
  }
  // Ids stay in 0 .. half the range (the studio refuses others): a shift that would take the
  // newest out of it (a hostile or confused studio) is refused.
  constexpr int64_t kMaxId = std::numeric_limits<int64_t>::max() / 2;
  int64_t current = id_offset_;
  const int64_t total = current + offset, newest = newest_raw_id_;
  if (std::abs(offset) > kMaxId || std::abs(total) > kMaxId || newest + total < 0 ||
      newest + total > kMaxId) {
    spdlog::warn(
        "node {}: the studio's shift of its frame ids by {} would take them out of range "
        "(newest {}): refused",
        name_, offset, newest + current);
    return;
  }
  if (!id_offset_.compare_exchange_strong(current, total)) return;  // its cameras restarted
  spdlog::warn(
      "node {}: its cameras count frame ids {} off the other nodes' cameras for the same instants "
      "(restarted alone?): its ids move by {} to follow them",
      name_, offset, total);
}

void CameraNode::silhouetteLoop(const std::atomic<bool>& stop) {
  while (!stop) {
    std::optional<std::shared_ptr<const Set>> set = sets_.pop(std::chrono::milliseconds(20));
    if (!set) continue;
    {
      std::lock_guard lock(kept_mutex_);
      // The cameras restarted (ids from near 0 again): the old sets go, or they would outlast every
      // new one (the lowest ids go first) and no pose would find its set again.
      if (!kept_.empty() && (*set)->frame_id < kept_.rbegin()->first - kFrameIdWindow)
        kept_.clear();
      kept_[(*set)->frame_id] = *set;
      while (static_cast<int>(kept_.size()) > options_.frames_kept) kept_.erase(kept_.begin());
    }
    Message silhouettes = silhouettesOf(**set);
    {
      std::lock_guard lock(monitor_mutex_);
      monitor_set_ = *set;
      monitor_silhouettes_ = std::get<SilhouettesData>(silhouettes.body).masks;
    }
    post(std::move(silhouettes));
  }
}

CameraNode::MonitorState CameraNode::monitorState() {
  MonitorState state;
  {
    std::lock_guard lock(monitor_mutex_);
    if (monitor_set_) {
      state.frame_id = monitor_set_->frame_id;
      state.keep_alive = monitor_set_;
      for (const CameraFrame& f : monitor_set_->frames) state.frames.push_back(&f);
    }
    state.silhouettes = monitor_silhouettes_;
  }
  {
    const std::unique_lock lock = lockSource();
    for (int c : cameras_) state.stats.push_back(source_->stats(c));
  }
  state.sets_sent = sets_sent_;
  state.bytes_sent = bytes_sent_;
  state.take = takes_.status();
  return state;
}

void CameraNode::statisticsLoop(const std::atomic<bool>& stop) {
  // The renderer's OpenGL context lives on this thread; made before the first pose arrives
  // (context and shaders take a while, longer on a loaded machine).
  try {
    gl_ = std::make_unique<EglContext>();
    renderer_ = std::make_unique<LumigraphRenderer>(rig_, cameras_);
  } catch (const Error& e) {
    spdlog::error("node {}: no lumigraph rendering: {}", name_, e.what());
  }
  int64_t failures = 0;
  while (!stop) {
    studio_work_.clear();
    // A frame the node cannot make (a view its GPU cannot hold, out of memory) is skipped and
    // said, and the node goes on with the next: an exception leaving this thread would end the
    // process.
    int64_t frame_id = -1;
    try {
      if (std::optional<Message> offsets = offsets_.pop(std::chrono::milliseconds(0))) {
        frame_id = offsets->frame_id;
        for (Message& image : partialImagesWithOffsets(*offsets)) post(std::move(image));
      } else if (std::optional<Message> pose = poses_.pop(std::chrono::milliseconds(0))) {
        frame_id = pose->frame_id;
        if (std::optional<Message> reply = statisticsFor(*pose)) post(std::move(*reply));
      } else {
        studio_work_.wait(std::chrono::milliseconds(20));
      }
    } catch (const std::exception& e) {
      if (++failures <= 10 || failures % 1000 == 0)
        spdlog::error("node {}: frame {} skipped ({} so far): {}", name_, frame_id, failures,
                      e.what());
    }
  }
  // The GL objects belong to this thread's context.
  renderer_.reset();
  gl_.reset();
}

void CameraNode::post(Message message) {
  outbox_.push(std::move(message));
  outbox_ready_.notify();
}

bool CameraNode::send(Message message) {
  message.sender = name_;
  const bool silhouettes = std::holds_alternative<SilhouettesData>(message.body);
  const std::span<const uint8_t> bytes = encoder_.encode(message);
  const bool sent = endpoint_.send(bytes, std::chrono::milliseconds(20));
  if (sent) {
    bytes_sent_ += static_cast<int64_t>(bytes.size());
    sets_sent_ += silhouettes;
  }
  return sent;
}

std::string CameraNode::sourceEnd() {
  const std::unique_lock lock = lockSource();
  std::string failure = source_->failure();
  return failure.empty() ? "its cameras' source delivered its last frame" : failure;
}

void CameraNode::run(const std::atomic<bool>& stop) {
  std::atomic<bool> stop_workers{false};
  std::thread capture([&] { captureLoop(stop_workers); });
  std::thread silhouettes([&] { silhouetteLoop(stop_workers); });
  std::thread statistics([&] { statisticsLoop(stop_workers); });
  auto last_heartbeat = std::chrono::steady_clock::now() - options_.heartbeat;
  auto last_from_studio = std::chrono::steady_clock::now();
  // Whether the studio has answered (it does once it hears the node): until then the node says,
  // every kNoAnswerEvery, that it has not, and what to check.
  constexpr auto kNoAnswerEvery = std::chrono::seconds(10);
  bool studio_answered = false;
  const auto started = std::chrono::steady_clock::now();
  auto told_no_answer = started;
  while (!stop && !source_finished_) {
    outbox_ready_.clear();
    while (std::optional<Message> out = outbox_.pop(std::chrono::milliseconds(0)))
      send(std::move(*out));
    // Woken by a message from the studio or one to send, else at least every 10 ms (heartbeats,
    // the stop flag).
    if (std::optional<DecodeResult> received =
            endpoint_.receive(std::chrono::milliseconds(10), outbox_ready_.fd())) {
      if (received->ok()) {
        last_from_studio = std::chrono::steady_clock::now();
        if (!studio_answered) spdlog::info("node {}: the studio answered", name_);
        studio_answered = true;
      }
      if (received->ok() && std::holds_alternative<PoseData>(received->message->body)) {
        poses_.push(std::move(*received->message));
        studio_work_.notify();
      } else if (received->ok() && std::holds_alternative<OffsetsData>(received->message->body)) {
        offsets_.push(std::move(*received->message));
        studio_work_.notify();
      } else if (received->ok() && std::holds_alternative<ViewData>(received->message->body)) {
        std::lock_guard lock(view_mutex_);
        const ViewData& view = std::get<ViewData>(received->message->body);
        views_[view.view] = view;
        keepView(received->message->frame_id, view);
      } else if (received->ok() && std::holds_alternative<RecordData>(received->message->body)) {
        takes_.command(std::get<RecordData>(received->message->body));
      } else if (received->ok() && std::holds_alternative<FrameIdsData>(received->message->body)) {
        followFrameIds(std::get<FrameIdsData>(received->message->body).offset);
      }
    }
    const auto now = std::chrono::steady_clock::now();
    if (!studio_answered && now - told_no_answer >= kNoAnswerEvery) {
      told_no_answer = now;
      spdlog::warn(
          "node {}: no answer from the studio at {} for {} s: is it running and listening there, "
          "is the TCP port open, and (unless --plain on both) is this node's key in the studio's "
          "key store?",
          name_, studio_address_,
          std::chrono::duration_cast<std::chrono::seconds>(now - started).count());
    }
    if (now - last_heartbeat >= options_.heartbeat) {
      last_heartbeat = now;
      HeartbeatData heartbeat;
      {
        const std::unique_lock lock = lockSource();
        for (size_t k = 0; k < cameras_.size(); ++k) {
          const int c = cameras_[k];
          const CameraStats s = source_->stats(c);
          heartbeat.cameras.push_back(
              {rig_.camera(c).name(), s.frames, s.dropped, float(s.frame_rate_hz),
               s.last_error.empty() ? screen_warnings_[k] : s.last_error, key_kinds_[k].load()});
        }
      }
      heartbeat.bytes_sent = bytes_sent_;
      if (now - last_from_studio > options_.unattended_take_limit) {
        takes_.abandon(fmt::format(
            "closed: no word from the studio for {} s",
            std::chrono::duration_cast<std::chrono::seconds>(options_.unattended_take_limit)
                .count()));
      }
      heartbeat.take = takes_.status();
      Message message;
      message.sent_ns = steadyNowNs();
      message.body = std::move(heartbeat);
      send(std::move(message));
    }
  }
  stop_workers = true;
  for (std::thread* t : {&capture, &silhouettes, &statistics}) t->join();
}

}  // namespace lumistage
