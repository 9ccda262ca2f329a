#include "core/pipeline/studio_coordinator.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <limits>
#include <utility>

#include "core/base/error.h"
#include "core/body/human_model.h"
#include "core/geometry/stage_volume.h"
#include "core/imaging/partial_image_codec.h"
#include "core/net/posed_body.h"
#include "core/render/lumigraph_renderer.h"

namespace lumistage {

namespace {

// Counts a node's message refused, and says why the first time (`told`: the node's flag for it).
template <typename Node, typename... Args>
void refuseSayingOnce(Node& node, bool& told, fmt::format_string<Args...> why, Args&&... args) {
  ++node.report.bad_messages;
  if (std::exchange(told, true)) return;
  spdlog::warn(why, std::forward<Args>(args)...);
}

// The default view (the constructor's): 320x240.
constexpr int64_t kDefaultViewPixels = 320 * 240;

int64_t largestViewPixels(const StudioCoordinatorOptions& options) {
  return std::max(options.max_view_pixels, kDefaultViewPixels);
}

// The endpoint's message size from what the nodes of this rig may send (largestNodeMessage), a
// quarter more to spare, never above what was asked for: every connection, before its handshake
// is done too, may make libzmq buffer a message this large, so that 64 MB let a few dozen hostile
// connections take gigabytes (issue 54).
StudioEndpointConfig limitedToTheRig(const Rig& rig, StudioEndpointConfig endpoint,
                                     const StudioCoordinatorOptions& options) {
  NodeMessageSizes sizes;
  sizes.cameras = rig.cameraCount();
  for (int c = 0; c < rig.cameraCount(); ++c)
    sizes.camera_pixels =
        std::max(sizes.camera_pixels, int64_t(rig.camera(c).width()) * rig.camera(c).height());
  sizes.silhouette_step = options.silhouette_step;
  // Statistics are of the body's vertices and their window points; without a body to tell, of
  // as many points as a message may hold.
  const int64_t points =
      options.body ? int64_t(options.body->rest.vertexCount()) * RefineConfig::kWindowPoints
                   : int64_t(endpoint.limits.max_vertices);
  sizes.statistics_samples = points * std::max(options.refine.offset_count, 1);
  sizes.view_pixels = largestViewPixels(options);
  const size_t largest = largestNodeMessage(sizes, endpoint.limits);
  endpoint.limits.max_bytes =
      std::min(endpoint.limits.max_bytes, largest + largest / 4 + (size_t{64} << 10));
  // Every node of the rig may run on one PC, and one coming back may briefly hold two
  // connections: the cap on an address leaves room for that.
  endpoint.max_connections_per_address =
      std::max(endpoint.max_connections_per_address, 2 * rig.nodeCount() + 2);
  return endpoint;
}

}  // namespace

StudioCoordinator::StudioCoordinator(const Rig& rig, StudioEndpointConfig endpoint,
                                     int body_joint_count, StudioCoordinatorOptions options)
    : rig_(rig),
      endpoint_(limitedToTheRig(rig, std::move(endpoint), options)),
      options_(options),
      stage_(chooseStage(rig)),
      locator_(rig, options.silhouette_step, 0.06, stage_.box),
      joints_(body_joint_count) {
  if (body_joint_count == kHumanJointCount) {
    // The nodes pose the generic human: the tracker fits (a calibrated copy of) its skeleton.
    const SkinnedMesh generic = loadGenericHuman();
    PoseTrackerOptions tracking;
    tracking.silhouette_step = options.silhouette_step;
    // The box chosen above (searched once); one worked out from the cameras is narrowed by the
    // tracker where its tables would not fit, one the rig file gives is taken as it is.
    tracking.stage = stage_.box;
    tracking.stage_from_cameras = !rig_.stage();
    tracker_ = std::make_unique<PoseTracker>(rig, generic, tracking);
    // Pose messages are fitted to the skeleton of the body the nodes pose (a file's own body
    // stands on its own proportions; either generic human on the generic skeleton).
    generic_skeleton_ = options.body ? options.body->skeleton : generic.skeleton;
  }
  if (stage_.guessed) {
    spdlog::warn("stage: {}", stage_.how);
  } else {
    spdlog::info("stage: {}", stage_.how);
  }
  for (size_t n = 0; n < rig_.nodes().size(); ++n) {
    NodeState& state = nodes_[rig_.nodes()[n].name];
    state.report.name = rig_.nodes()[n].name;
    state.index = int(n);
  }
  timeline_.reserve(4096);
  statistics_deadline_ns_ = image_deadline_ns_ =
      std::chrono::nanoseconds(options_.deadline).count();
  instants_.fill({-1, 0});
  // Default view: 320x240 from the front-left, 4.5 m out and 1.7 m up, looking at the stage
  // centre 1 m above the floor (camera axes: x right, y down, z forward).
  const Eigen::Vector3f centre(-3.2f, -3.2f, 1.7f), target(0, 0, 1.0f);
  const Eigen::Vector3f z = (target - centre).normalized();
  const Eigen::Vector3f x = z.cross(Eigen::Vector3f::UnitZ()).normalized();
  const Eigen::Vector3f y = z.cross(x);
  ViewData view = {0, 320, 240, 300, 300, 159.5f, 119.5f, {}, {}, {}};
  for (const Eigen::Vector3f& row : {x, y, z}) {
    for (int k = 0; k < 3; ++k) view.rotation.push_back(row[k]);
  }
  view.translation = {-x.dot(centre), -y.dot(centre), -z.dot(centre)};
  views_.push_back(view);
  mocap_thread_ = std::thread([this] { mocapLoop(); });
}

StudioCoordinator::~StudioCoordinator() {
  mocap_jobs_.close();
  mocap_thread_.join();
}

bool StudioCoordinator::acceptsView(const ViewData& view) const {
  if (int64_t(view.width) * view.height <= largestViewPixels(options_)) return true;
  // The nodes' images of it would be larger than the endpoint takes: each would cost its node
  // the connection.
  spdlog::error(
      "studio: view {} of {}x{} is larger than the {} pixels the studio was started for: not used",
      view.view, view.width, view.height, largestViewPixels(options_));
  return false;
}

void StudioCoordinator::setView(const ViewData& view) {
  if (!acceptsView(view)) return;
  for (ViewData& v : views_) {
    if (v.view == view.view) {
      v = view;
      return;
    }
  }
  views_.push_back(view);
}

void StudioCoordinator::setViews(std::vector<ViewData> views) {
  for (const ViewData& view : views)
    if (!acceptsView(view)) return;
  if (!views.empty()) views_ = std::move(views);
}

void StudioCoordinator::removeView(int view) {
  if (views_.size() <= 1) return;  // always at least one
  std::erase_if(views_, [&](const ViewData& v) { return v.view == view; });
}

const BlendedImage& StudioCoordinator::lastImage(int view) const {
  static const BlendedImage kNone;
  const auto it = last_images_.find(view);
  return it == last_images_.end() ? kNone : it->second;
}

void StudioCoordinator::maybeFinish(int64_t frame_id, FrameState& frame) {
  if (frame.offsets_sent_ns == 0 && frame.statistics_nodes.size() >= frame.pose_nodes.size()) {
    runRefinement(frame_id, frame);
    return;
  }
  if (frame.offsets_sent_ns == 0) return;
  // Every view's image from every node whose statistics were refined (a node whose statistics
  // came late still renders and is blended, but is not waited for, nor counts for one that is).
  for (const auto& [view, width, height] : frame.views) {
    const auto it = frame.image_nodes.find(view);
    if (it == frame.image_nodes.end()) return;
    for (const std::string& node : frame.statistics_nodes)
      if (!it->second.count(node)) return;
  }
  finishFrame(frame_id, frame);
}

std::string StudioCoordinator::nodeState(const std::string& node) const {
  const auto it = nodes_.find(node);
  if (it == nodes_.end() || it->second.last_ns == 0) return "unknown";
  return it->second.report.lost ? "lost" : "streaming";
}

Status StudioCoordinator::startTake(const std::string& take) {
  if (Status named = checkTakeName(take); !named.ok()) return named;
  if (recordingTake())
    return Status::failure("take " + take_.take + " is recording: stop it first");
  if (take == take_.take)
    return Status::failure("take " + take + " was recorded already: give the next a new name");
  take_ = RecordData{take, std::max<int64_t>(0, newest_seen_ + kTakeLeadFrames)};
  spdlog::info("take {}: recording from frame {}", take_.take, take_.first_frame);
  for (auto& [name, node] : nodes_) sendTake(node);
  return {};
}

void StudioCoordinator::stopTake() {
  if (!recordingTake()) return;
  take_.last_frame = std::max(take_.first_frame, newest_seen_ + kTakeLeadFrames);
  spdlog::info("take {}: frames {} to {}", take_.take, take_.first_frame, take_.last_frame);
  for (auto& [name, node] : nodes_) sendTake(node);
}

void StudioCoordinator::sendTake(NodeState& node) {
  if (node.report.lost || node.peer.empty()) return;
  Message message;
  message.sender = "studio";
  message.sent_ns = steadyNowNs();
  message.body = take_;
  endpoint_.send(node.peer, encoder_.encode(message), std::chrono::milliseconds(5));
}

void StudioCoordinator::onMessage(const ReceivedMessage& received) {
  const auto node_it = nodes_.find(received.node);
  if (node_it == nodes_.end()) return;  // authorised but not in this rig: ignored
  NodeState& node = node_it->second;
  noteHeard(node, received);
  if (!received.result.ok()) {
    ++node.report.bad_messages;
    return;
  }
  const Message& message = *received.result.message;
  ++node.report.messages;
  if (counting_) {
    node.counted_bytes += int64_t(received.bytes);
    node.counted_to_ns = node.last_ns;
  }
  if (const auto* heartbeat = std::get_if<HeartbeatData>(&message.body)) {
    onHeartbeat(node, *heartbeat);
    return;
  }
  if (std::holds_alternative<SilhouettesData>(message.body) && !noteSilhouettes(node, message))
    return;
  timeAnswer(node, message);
  if (message.frame_id <= newest_done_) return;  // a frame already done or given up
  if (std::find(refused_.begin(), refused_.end(), message.frame_id) != refused_.end())
    return;  // dropped at admission
  if (const auto* silhouettes = std::get_if<SilhouettesData>(&message.body)) {
    onSilhouettes(node, message.frame_id, message.sent_ns, *silhouettes, received.bytes);
  } else if (const auto* stats = std::get_if<VertexStatisticsData>(&message.body)) {
    onStatistics(node, message.frame_id, *stats, received.bytes);
  } else if (const auto* image = std::get_if<PartialImageData>(&message.body)) {
    onImage(node, message.frame_id, *image, received.bytes);
  }
}

void StudioCoordinator::noteHeard(NodeState& node, const ReceivedMessage& received) {
  node.peer = received.peer;
  node.last_ns = steadyNowNs();
  if (node.heard_ns == 0 || node.report.lost) node.heard_ns = node.last_ns;
  if (first_message_ns_ == 0) first_message_ns_ = node.last_ns;
  if (!counting_) {
    bool all = true;
    for (const auto& [name, n] : nodes_) all = all && n.last_ns > 0;
    counting_ = all || node.last_ns - first_message_ns_ > 3'000'000'000;
    if (counting_) counting_since_ns_ = node.last_ns;
  }
  if (node.report.lost) {
    node.report.lost = false;
    // What it recorded before it was lost is not what it records now (a node restarted mid-take
    // starts a part of its own): its next heartbeat says.
    node.report.take = {};
    spdlog::info("node {} is streaming", node.report.name);
    sendTake(node);  // the take under way, if any: and the node's word that it reached the studio
  }
}

void StudioCoordinator::onHeartbeat(NodeState& node, const HeartbeatData& heartbeat) {
  node.report.bytes = heartbeat.bytes_sent;  // what the node says it has sent in all
  node.report.cameras.clear();
  // Camera names were checked by the decoder; the free text a node sends (its cameras' errors,
  // its take's error and disk) reaches the log, `lumistage run`'s report and the health panel
  // escaped and cut short, so that no node can forge a line or move a terminal's cursor there.
  for (const CameraHealthData& c : heartbeat.cameras) {
    node.report.cameras.push_back({c.camera, c.frames, c.dropped, c.frame_rate,
                                   printableInput(c.last_error), printableInput(c.key, 64)});
  }
  node.report.take = heartbeat.take;
  node.report.take.error = printableInput(heartbeat.take.error);
  node.report.take.disk = printableInput(heartbeat.take.disk, 64);
  // A node that missed the take's command (or its stop), or came back during it: told again.
  // One still recording a take this studio never asked for (the studio restarted mid-take):
  // told to stop, rather than fill its disk unattended.
  const TakeStatusData& t = heartbeat.take;
  const bool stale = take_.take.empty()
                         ? !t.take.empty() && !t.finished
                         : t.take != take_.take || t.first_frame != take_.first_frame ||
                               t.last_frame != take_.last_frame;
  // While a take records, every heartbeat is answered: the node's word that the studio is
  // still there (it closes a take after --unattended-take-limit of silence).
  if (stale || recordingTake()) sendTake(node);
}

bool StudioCoordinator::noteSilhouettes(NodeState& node, const Message& message) {
  if (!acceptFrameId(node, message.frame_id)) {
    ++node.report.bad_messages;
    return false;
  }
  newest_seen_ = std::max(newest_seen_, message.frame_id);  // where the cameras are (takes)
  node.silhouettes_ns = node.last_ns;
  // Silhouettes flowing again after none for lost_after (the start, cameras back): every node is
  // given lost_after from here.
  if (node.last_ns - newest_silhouettes_ns_ > std::chrono::nanoseconds(options_.lost_after).count())
    silhouettes_began_ns_ = node.last_ns;
  newest_silhouettes_ns_ = node.last_ns;
  if (node.told_no_frames) {
    node.told_no_frames = false;
    spdlog::info("node {}: its silhouettes are used again", node.report.name);
  }
  return true;
}

void StudioCoordinator::timeAnswer(NodeState& node, const Message& message) {
  // Every answer is timed, in time or late, for the deadlines (updateDeadlines).
  if (const SentAt& sent = sentAt(message.frame_id); sent.frame_id == message.frame_id) {
    if (std::holds_alternative<VertexStatisticsData>(message.body) && sent.pose_ns > 0)
      node.statistics_answers.add(double(node.last_ns - sent.pose_ns) / 1e6);
    const auto* image = std::get_if<PartialImageData>(&message.body);
    if (image && sent.offsets_ns > 0 && !views_.empty() && image->view == views_.front().view)
      node.image_answers.add(double(node.last_ns - sent.offsets_ns) / 1e6);
  }
}

void StudioCoordinator::onSilhouettes(NodeState& node, int64_t frame_id, int64_t sent_ns,
                                      const SilhouettesData& silhouettes, size_t bytes) {
  FrameState& frame = frameState(frame_id);
  if (frame.first_ns == 0) {
    frame.first_ns = node.last_ns;
    frame.captured_ns = sent_ns;
  }
  frame.captured_ns = std::min(frame.captured_ns, sent_ns);
  frame.addBytes(node.index, bytes);
  for (const SilhouetteMaskData& mask : silhouettes.masks) {
    // Only the node's own cameras, once a frame: a node with another rig file (other cameras at
    // its places) would otherwise carve the hull with masks of the wrong cameras, the last one
    // to arrive winning.
    const bool own = mask.camera >= 0 && mask.camera < rig_.cameraCount() &&
                     rig_.nodes()[rig_.nodeOfCamera(mask.camera)].name == node.report.name;
    if (!own || std::any_of(frame.silhouettes.begin(), frame.silhouettes.end(),
                            [&](const LowResSilhouette& s) { return s.camera == mask.camera; })) {
      ++node.report.bad_messages;
      continue;
    }
    // The tracker indexes cells by the camera's size: a mask of another size (a node of an
    // older version, at another step) is not used, and said once.
    const Camera& camera = rig_.camera(mask.camera);
    if (mask.width != camera.width() / options_.silhouette_step ||
        mask.height != camera.height() / options_.silhouette_step) {
      refuseSayingOnce(
          node, node.told_silhouette_size,
          "node {}: camera {}: silhouette of {}x{} cells, the studio tracks from {}x{} (cells of "
          "{} pixels): not used; is the node of another version?",
          node.report.name, camera.name(), mask.width, mask.height,
          camera.width() / options_.silhouette_step, camera.height() / options_.silhouette_step,
          options_.silhouette_step);
      continue;
    }
    LowResSilhouette s;
    s.camera = mask.camera;
    s.step = options_.silhouette_step;
    s.width = mask.width;
    s.height = mask.height;
    s.bits = mask.bits;  // the same packing on the wire and in memory
    frame.silhouettes.push_back(std::move(s));
    frame.colours.push_back(mask.colours);  // the actor's, on the frames a node samples them
  }
  frame.silhouette_nodes.insert(node.report.name);
  int live = 0;
  for (const auto& [name, n] : nodes_) live += awaited(n);
  if (!frame.mocap_begun && static_cast<int>(frame.silhouette_nodes.size()) >= live)
    beginMocap(frame_id, frame);
}

void StudioCoordinator::onStatistics(NodeState& node, int64_t frame_id,
                                     const VertexStatisticsData& stats, size_t bytes) {
  const auto it = frames_.find(frame_id);
  if (it == frames_.end() || it->second.pose_sent_ns == 0 || it->second.offsets_sent_ns > 0) return;
  FrameState& frame = it->second;
  if (frame.statistics_nodes.count(node.report.name)) return;
  frame.addBytes(node.index, bytes);
  const int colour_bits = stats.packed.size() >= 8 ? stats.packed[5] : 0;
  if (stats.offset_count != options_.refine.offset_count || colour_bits < 1 || colour_bits > 8) {
    refuseSayingOnce(
        node, node.told_statistics,
        "node {}: frame {}: refinement statistics at {} offsets and {} colour bits, the studio "
        "refines at {} offsets: not used; is the node's refine: configuration another?",
        node.report.name, frame_id, stats.offset_count, colour_bits, options_.refine.offset_count);
    return;
  }
  // Of the body's vertices (alone, or with their window points), where the studio knows the
  // body: otherwise the first node to answer, with another mesh, set the sum's sizes and every
  // node with the right one was refused.
  if (options_.body && !bodyFits(refinedVertices(int(stats.vertex_count)))) {
    refuseSayingOnce(
        node, node.told_statistics,
        "node {}: frame {}: refinement statistics of {} points, not of the body's {} vertices: "
        "not used; does the node pose another body?",
        node.report.name, frame_id, stats.vertex_count, options_.body->rest.vertexCount());
    return;
  }
  if (frame.refine_sum.vertex_count == 0)
    frame.refine_sum.reset(int(stats.vertex_count), stats.offset_count, colour_bits);
  // Integer sums of every node's cameras add up exactly, in any order.
  if (const Status added = statistics_codec_.add(stats.packed, frame.refine_sum); !added.ok()) {
    spdlog::warn("node {}: frame {}: {}", node.report.name, frame_id, added.error());
    ++node.report.bad_messages;
    // The first node's statistics set the sum's sizes: when they were refused, the next node's
    // set them again, rather than be refused for differing from them.
    if (frame.statistics_nodes.empty()) frame.refine_sum.vertex_count = 0;
    return;
  }
  frame.statistics_nodes.insert(node.report.name);
  node.statistics_ms.add((steadyNowNs() - frame.pose_sent_ns) / 1e6);
  maybeFinish(frame_id, frame);
}

void StudioCoordinator::onImage(NodeState& node, int64_t frame_id, const PartialImageData& image,
                                size_t bytes) {
  const auto it = frames_.find(frame_id);
  if (it == frames_.end() || it->second.pose_sent_ns == 0) return;
  FrameState& frame = it->second;
  const std::array<int, 3> asked{image.view, image.width, image.height};
  if (std::find(frame.views.begin(), frame.views.end(), asked) == frame.views.end())
    return;  // not a view (of that size) sent with the frame's pose
  // Once a node and view: a repeated image would be blended twice.
  if (frame.image_nodes[image.view].count(node.report.name)) return;
  frame.addBytes(node.index, bytes);
  const size_t pixels = size_t(image.width) * image.height;
  PartialImageBlender& blender = frame.blends[image.view];
  if (blender.width() != image.width || blender.height() != image.height)
    blender.reset(image.width, image.height);
  // The paper's blend: colours add weighted by the nodes' alphas, normalised at the end. An
  // image that arrives in alpha runs is added from them: only the actor's pixels are touched.
  bool added = false;
  if (image.encoding == ImageEncoding::kAlphaRuns) {
    added = blender.addAlphaRuns(image.data);
  } else if (image.encoding == ImageEncoding::kRleRgba) {
    decoded_ = decodeRleRgba(image.data, pixels);
    added = blender.add(decoded_);
  } else {
    added = blender.add(image.data);
  }
  if (!added) return;
  if (frame.offsets_out_ns > 0 && image.view == views_.front().view)
    node.image_ms.add((steadyNowNs() - frame.offsets_out_ns) / 1e6);
  frame.image_nodes[image.view].insert(node.report.name);
  maybeFinish(frame_id, frame);
}

bool StudioCoordinator::awaited(const NodeState& node) const {
  if (node.report.lost || node.last_ns == 0) return false;
  // Left out once other nodes' silhouettes have come for lost_after without its own (since it was
  // heard, or its last): judged against the others, not the clock, so that nodes whose cameras are
  // slow to start (nobody's silhouettes yet) all stay awaited.
  const int64_t since = std::max({node.silhouettes_ns, node.heard_ns, silhouettes_began_ns_});
  return newest_silhouettes_ns_ - since <= std::chrono::nanoseconds(options_.lost_after).count();
}

void StudioCoordinator::updateDeadlines() {
  const int64_t base = std::chrono::nanoseconds(options_.deadline).count();
  const int64_t most =
      std::max(base, int64_t(std::chrono::nanoseconds(options_.max_deadline).count()));
  const auto follow = [&](RecentSamples NodeState::*answers) {
    double slowest_ms = 0;
    for (const auto& [name, node] : nodes_) {
      const std::vector<double>& values = (node.*answers).values();
      if (!awaited(node) || values.size() < 8) continue;
      quantile_scratch_.assign(values.begin(), values.end());
      slowest_ms = std::max(slowest_ms, quantile(quantile_scratch_, 0.9));
    }
    return std::clamp(int64_t(1.25 * slowest_ms * 1e6), base, most);
  };
  // Once stretched, they follow until the nodes answer within `deadline` again (follow() gives
  // the base then), not until the frames are whole again: they are whole because the deadlines
  // follow, and going back at once made a slow node miss again, a frame in three or four (its
  // three fellows' work and the studio's lost).
  if (!deadlinesFollowing() && incomplete_share_ < 0.25) {
    statistics_deadline_ns_ = image_deadline_ns_ = base;
    return;
  }
  statistics_deadline_ns_ = follow(&NodeState::statistics_answers);
  image_deadline_ns_ = follow(&NodeState::image_answers);
}

void StudioCoordinator::checkDeadlines(int64_t now_ns) {
  const int64_t deadline = std::chrono::nanoseconds(options_.deadline).count();
  for (auto& [name, node] : nodes_) {
    if (!node.report.lost && !node.told_no_frames && node.last_ns > 0 && !awaited(node)) {
      node.told_no_frames = true;
      spdlog::warn(
          "node {} is heard but none of its silhouettes was used for {} ms (cameras? frame ids "
          "far from the others'? another version?): frames go on without it",
          name, options_.lost_after.count());
    }
    if (!node.report.lost && node.last_ns > 0 &&
        now_ns - node.last_ns > std::chrono::nanoseconds(options_.lost_after).count()) {
      node.report.lost = true;
      ++node.report.times_lost;
      spdlog::warn("node {} is lost: nothing for {} ms", name, options_.lost_after.count());
    }
  }
  for (auto it = frames_.begin(); it != frames_.end();) {
    const int64_t frame_id = it->first;
    FrameState& frame = it->second;
    ++it;  // finishFrame may erase this and earlier frames, beginMocap this and another
    if (!frame.mocap_begun && now_ns - frame.first_ns > deadline) {
      beginMocap(frame_id, frame);  // with the nodes that made it
      it = frames_.upper_bound(frame_id);
    } else if (frame.pose_sent_ns > 0 && frame.offsets_sent_ns == 0 &&
               now_ns - frame.pose_sent_ns > statistics_deadline_ns_) {
      runRefinement(frame_id, frame);  // with the nodes' statistics that made it
      it = frames_.upper_bound(frame_id);
    } else if (frame.offsets_sent_ns > 0 && now_ns - frame.offsets_sent_ns > image_deadline_ns_) {
      finishFrame(frame_id, frame);
      it = frames_.upper_bound(frame_id);
    }
  }
}

void StudioCoordinator::pump() {
  // Everything waiting is read before the deadlines are looked at: after a long stage here (the
  // tracker's first frame takes a second) a node whose messages wait in the socket is not lost.
  std::chrono::milliseconds wait(10);
  for (int n = 0; n < 256; ++n, wait = std::chrono::milliseconds(0)) {
    std::optional<ReceivedMessage> received = endpoint_.receive(wait, mocap_ready_.fd());
    if (!received) break;
    onMessage(*received);
    // A pose the tracker finished meanwhile goes out at once: it is the newest frame's path to
    // the nodes, and the backlog behind it (older frames' statistics and images, a refinement
    // or a blend each) would hold it for tens of milliseconds after a burst.
    if (mocap_done_.size() > 0) takePoses();
  }
  takePoses();
  checkDeadlines(steadyNowNs());
}

void StudioCoordinator::runFor(std::chrono::milliseconds duration) {
  const int64_t end = steadyNowNs() + std::chrono::nanoseconds(duration).count();
  while (steadyNowNs() < end && (options_.max_frames == 0 || frames_done_ < options_.max_frames))
    pump();
}

void StudioCoordinator::run(const std::atomic<bool>& stop) {
  while (!stop && (options_.max_frames == 0 || frames_done_ < options_.max_frames)) pump();
}

const NodeReport* fullestTakeDisk(const RunReport& report) {
  const NodeReport* fullest = nullptr;
  for (const NodeReport& n : report.nodes) {
    if (!n.lost && n.take_seconds_left >= 0 &&
        (!fullest || n.take_seconds_left < fullest->take_seconds_left))
      fullest = &n;
  }
  return fullest;
}

RunReport StudioCoordinator::report() const {
  RunReport r;
  r.frames = frames_done_;
  r.frames_dropped = frames_refused_ + frames_overtaken_ + frames_unshown_;
  r.frames_refused = frames_refused_;
  r.frames_overtaken = frames_overtaken_;
  r.frames_unshown = frames_unshown_;
  r.frames_incomplete = frames_incomplete_;
  r.frames_held = frames_held_;
  r.statistics_deadline_ms = double(statistics_deadline_ns_) / 1e6;
  r.image_deadline_ms = double(image_deadline_ns_) / 1e6;
  r.deadlines_following = deadlinesFollowing();
  r.peak_frames_begun = peak_frames_begun_;
  r.fps = frames_done_ > 1 && last_done_ns_ > start_ns_
              ? (frames_done_ - 1) / ((last_done_ns_ - start_ns_) / 1e9)
              : 0;
  r.fps_recent = eventsPerSecond(recent_done_ns_.values());
  std::vector<double> latencies = latencies_ms_.values();
  r.latency_ms_p50 = quantile(latencies, 0.5);
  r.latency_ms_p95 = quantile(latencies, 0.95);
  r.timeline.reserve(timeline_.size());
  for (const auto& [done_ns, latency_ms] : timeline_)
    r.timeline.push_back({(done_ns - start_ns_) / 1e9, latency_ms});
  auto mean = [](const RecentSamples& s) {
    double sum = 0;
    for (double v : s.values()) sum += v;
    return s.values().empty() ? 0.0 : sum / s.values().size();
  };
  r.stage_ms["mocap"] = mean(mocap_ms_);
  r.stage_ms["nodes_statistics_and_render"] = mean(statistics_wait_ms_);
  r.stage_ms["refine"] = mean(refine_ms_);
  r.stage_ms["visibility"] = mean(visibility_ms_);
  r.stage_ms["combine"] = mean(combine_ms_);
  r.stage_ms["blend"] = mean(blend_ms_);
  for (size_t i = 0; i < kLatencyParts.size(); ++i)
    r.latency_parts_ms.emplace_back(kLatencyParts[i], mean(latency_parts_ms_[i]));
  r.hull_agreement = frames_done_ > 0 ? hull_agreement_sum_ / frames_done_ : 0;
  r.frames_tracked = frames_tracked_;
  double per_second = 0, raw = 0;
  std::map<std::string, double> take_bytes_per_s;  // by disk
  int64_t shown_bytes = 0, shown_frames = 0;
  int counted = 0;
  for (const RigNode& node : rig_.nodes()) {
    const NodeState& state = nodes_.at(node.name);
    r.nodes.push_back(state.report);
    r.nodes.back().bytes_per_frame =
        state.shown_frames > 0 ? double(state.shown_bytes) / double(state.shown_frames) : -1;
    shown_bytes += state.shown_bytes;
    shown_frames += state.shown_frames;
    const double node_raw = double(rig_.pixelsPerSet(node.cameras)) * options_.raw_bytes_per_pixel;
    double rate_hz = 0;
    for (const CameraHealth& c : state.report.cameras) rate_hz = std::max(rate_hz, c.frame_rate_hz);
    // What a take of its cameras writes a second, on the disk it names (nodes on one PC share
    // one: their rates add up below).
    if (!state.report.take.disk.empty())
      take_bytes_per_s[state.report.take.disk] += node_raw * rate_hz;
    raw += node_raw;
    if (state.counted_to_ns > counting_since_ns_ && counting_since_ns_ > 0) {
      per_second +=
          double(state.counted_bytes) / ((state.counted_to_ns - counting_since_ns_) / 1e9);
      ++counted;
    }
  }
  for (NodeReport& n : r.nodes) {
    const auto shared = take_bytes_per_s.find(n.take.disk);
    if (n.take.free_bytes >= 0 && shared != take_bytes_per_s.end() && shared->second > 0)
      n.take_seconds_left = double(n.take.free_bytes) / shared->second;
  }
  r.node_bytes_per_frame = shown_frames > 0 ? double(shown_bytes) / double(shown_frames) : 0;
  r.node_bytes_per_s = counted > 0 ? per_second / counted : 0;
  r.raw_bytes_per_frame_per_node = rig_.nodeCount() > 0 ? raw / rig_.nodeCount() : 0;
  r.refusals = endpoint_.refusalCount() + endpoint_.handshakeFailures();
  r.frames_in_flight = static_cast<int>(frames_.size());
  const int64_t now = steadyNowNs();
  for (NodeReport& n : r.nodes) {
    const NodeState& state = nodes_.at(n.name);
    n.silent_ms = state.last_ns > 0 ? (now - state.last_ns) / 1e6 : -1;
    auto median = [](const RecentSamples& s) {
      std::vector<double> v = s.values();
      return v.empty() ? -1.0 : quantile(v, 0.5);
    };
    n.statistics_ms = median(state.statistics_ms);
    n.image_ms = median(state.image_ms);
  }
  // Those the transport could not decode, and those decoded but refused here (statistics).
  const auto bad = endpoint_.badMessages();
  for (NodeReport& n : r.nodes) {
    if (const auto it = bad.find(n.name); it != bad.end()) n.bad_messages += it->second;
  }
  return r;
}

}  // namespace lumistage
