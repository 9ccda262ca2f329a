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
#include "core/pipeline/posed_body.h"
#include "core/render/lumigraph_renderer.h"
#include "core/render/partial_image_codec.h"

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
    generic_skeleton_ = generic.skeleton;
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

std::string StudioCoordinator::startTake(const std::string& take) {
  if (std::string error = takeNameError(take); !error.empty()) return error;
  if (recordingTake()) return "take " + take_.take + " is recording: stop it first";
  if (take == take_.take) return "take " + take + " was recorded already: give the next a new name";
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
    node.report.bytes = heartbeat->bytes_sent;  // what the node says it has sent in all
    node.report.cameras.clear();
    // Camera names were checked by the decoder; the free text a node sends (its cameras' errors,
    // its take's error and disk) reaches the log, `lumistage run`'s report and the health panel
    // escaped and cut short, so that no node can forge a line or move a terminal's cursor there.
    for (const CameraHealthData& c : heartbeat->cameras) {
      node.report.cameras.push_back(
          {c.camera, c.frames, c.dropped, c.frame_rate, printableInput(c.last_error)});
    }
    node.report.take = heartbeat->take;
    node.report.take.error = printableInput(heartbeat->take.error);
    node.report.take.disk = printableInput(heartbeat->take.disk, 64);
    // A node that missed the take's command (or its stop), or came back during it: told again.
    // One still recording a take this studio never asked for (the studio restarted mid-take):
    // told to stop, rather than fill its disk unattended.
    const TakeStatusData& t = heartbeat->take;
    const bool stale = take_.take.empty()
                           ? !t.take.empty() && !t.finished
                           : t.take != take_.take || t.first_frame != take_.first_frame ||
                                 t.last_frame != take_.last_frame;
    // While a take records, every heartbeat is answered: the node's word that the studio is
    // still there (it closes a take after --unattended-take-limit of silence).
    if (stale || recordingTake()) sendTake(node);
    return;
  }
  if (std::holds_alternative<SilhouettesData>(message.body)) {
    if (!acceptFrameId(node, message.frame_id)) {
      ++node.report.bad_messages;
      return;
    }
    newest_seen_ = std::max(newest_seen_, message.frame_id);  // where the cameras are (takes)
    node.silhouettes_ns = node.last_ns;
    // Silhouettes flowing again after none for lost_after (the start, cameras back): every node is
    // given lost_after from here.
    if (node.last_ns - newest_silhouettes_ns_ >
        std::chrono::nanoseconds(options_.lost_after).count())
      silhouettes_began_ns_ = node.last_ns;
    newest_silhouettes_ns_ = node.last_ns;
    if (node.told_no_frames) {
      node.told_no_frames = false;
      spdlog::info("node {}: its silhouettes are used again", node.report.name);
    }
  }
  // Every answer is timed, in time or late, for the deadlines (updateDeadlines).
  if (const SentAt& sent = sentAt(message.frame_id); sent.frame_id == message.frame_id) {
    if (std::holds_alternative<VertexStatisticsData>(message.body) && sent.pose_ns > 0)
      node.statistics_answers.add(double(node.last_ns - sent.pose_ns) / 1e6);
    const auto* image = std::get_if<PartialImageData>(&message.body);
    if (image && sent.offsets_ns > 0 && !views_.empty() && image->view == views_.front().view)
      node.image_answers.add(double(node.last_ns - sent.offsets_ns) / 1e6);
  }
  if (message.frame_id <= newest_done_) return;  // a frame already done or given up
  if (std::find(refused_.begin(), refused_.end(), message.frame_id) != refused_.end())
    return;  // dropped at admission
  if (const auto* silhouettes = std::get_if<SilhouettesData>(&message.body)) {
    FrameState& frame = frameState(message.frame_id);
    if (frame.first_ns == 0) {
      frame.first_ns = node.last_ns;
      frame.captured_ns = message.sent_ns;
    }
    frame.captured_ns = std::min(frame.captured_ns, message.sent_ns);
    frame.addBytes(node.index, received.bytes);
    for (const SilhouetteMaskData& mask : silhouettes->masks) {
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
    }
    frame.silhouette_nodes.insert(node.report.name);
    int live = 0;
    for (const auto& [name, n] : nodes_) live += awaited(n);
    if (!frame.mocap_begun && static_cast<int>(frame.silhouette_nodes.size()) >= live)
      beginMocap(message.frame_id, frame);
  } else if (const auto* stats = std::get_if<VertexStatisticsData>(&message.body)) {
    const auto it = frames_.find(message.frame_id);
    if (it == frames_.end() || it->second.pose_sent_ns == 0 || it->second.offsets_sent_ns > 0)
      return;
    FrameState& frame = it->second;
    if (frame.statistics_nodes.count(node.report.name)) return;
    frame.addBytes(node.index, received.bytes);
    const int colour_bits = stats->packed.size() >= 8 ? stats->packed[5] : 0;
    if (stats->offset_count != options_.refine.offset_count || colour_bits < 1 || colour_bits > 8) {
      refuseSayingOnce(
          node, node.told_statistics,
          "node {}: frame {}: refinement statistics at {} offsets and {} colour bits, the studio "
          "refines at {} offsets: not used; is the node's refine: configuration another?",
          node.report.name, message.frame_id, stats->offset_count, colour_bits,
          options_.refine.offset_count);
      return;
    }
    // Of the body's vertices (alone, or with their window points), where the studio knows the
    // body: otherwise the first node to answer, with another mesh, set the sum's sizes and every
    // node with the right one was refused.
    if (options_.body && !bodyFits(refinedVertices(int(stats->vertex_count)))) {
      refuseSayingOnce(
          node, node.told_statistics,
          "node {}: frame {}: refinement statistics of {} points, not of the body's {} vertices: "
          "not used; does the node pose another body?",
          node.report.name, message.frame_id, stats->vertex_count,
          options_.body->rest.vertexCount());
      return;
    }
    if (frame.refine_sum.vertex_count == 0)
      frame.refine_sum.reset(int(stats->vertex_count), stats->offset_count, colour_bits);
    // Integer sums of every node's cameras add up exactly, in any order.
    std::string error;
    if (!statistics_codec_.add(stats->packed, frame.refine_sum, &error)) {
      spdlog::warn("node {}: frame {}: {}", node.report.name, message.frame_id, error);
      ++node.report.bad_messages;
      // The first node's statistics set the sum's sizes: when they were refused, the next node's
      // set them again, rather than be refused for differing from them.
      if (frame.statistics_nodes.empty()) frame.refine_sum.vertex_count = 0;
      return;
    }
    frame.statistics_nodes.insert(node.report.name);
    node.statistics_ms.add((steadyNowNs() - frame.pose_sent_ns) / 1e6);
    maybeFinish(message.frame_id, frame);
  } else if (const auto* image = std::get_if<PartialImageData>(&message.body)) {
    const auto it = frames_.find(message.frame_id);
    if (it == frames_.end() || it->second.pose_sent_ns == 0) return;
    FrameState& frame = it->second;
    const std::array<int, 3> asked{image->view, image->width, image->height};
    if (std::find(frame.views.begin(), frame.views.end(), asked) == frame.views.end())
      return;  // not a view (of that size) sent with the frame's pose
    // Once a node and view: a repeated image would be blended twice.
    if (frame.image_nodes[image->view].count(node.report.name)) return;
    frame.addBytes(node.index, received.bytes);
    const size_t pixels = size_t(image->width) * image->height;
    PartialImageBlender& blender = frame.blends[image->view];
    if (blender.width() != image->width || blender.height() != image->height)
      blender.reset(image->width, image->height);
    // The paper's blend: colours add weighted by the nodes' alphas, normalised at the end. An
    // image that arrives in alpha runs is added from them: only the actor's pixels are touched.
    bool added = false;
    if (image->encoding == ImageEncoding::kAlphaRuns) {
      added = blender.addAlphaRuns(image->data);
    } else if (image->encoding == ImageEncoding::kRleRgba) {
      decoded_ = decodeRleRgba(image->data, pixels);
      added = blender.add(decoded_);
    } else {
      added = blender.add(image->data);
    }
    if (!added) return;
    if (frame.offsets_out_ns > 0 && image->view == views_.front().view)
      node.image_ms.add((steadyNowNs() - frame.offsets_out_ns) / 1e6);
    frame.image_nodes[image->view].insert(node.report.name);
    maybeFinish(message.frame_id, frame);
  }
}

bool StudioCoordinator::acceptFrameId(NodeState& node, int64_t frame_id) {
  // Ids beyond half the range leave no room to count on (takes start ahead of the newest).
  if (frame_id < 0 || frame_id > std::numeric_limits<int64_t>::max() / 2) return false;
  node.newest_frame = frame_id;
  const auto near = [](int64_t a, int64_t b) { return std::abs(a - b) <= kFrameIdWindow; };
  if (newest_seen_ < 0 || near(frame_id, newest_seen_)) {
    node.told_frame_id = false;
    node.refused_since_ns = 0;
    node.times_told = 0;
    // The frame's first arrival (a straggler of an older id, 64 or more back, leaves the slot
    // alone), and how far behind it this node's silhouettes come: its usual lag.
    auto& [id, arrived_ns] = instants_[size_t(frame_id) % kInstants];
    if (frame_id > id) id = frame_id, arrived_ns = node.last_ns;
    if (id == frame_id) {
      const int64_t lag = node.last_ns - arrived_ns;
      node.lag_ns = node.lag_ns == 0 ? lag : (7 * node.lag_ns + lag) / 8;
    }
    return true;
  }
  // The nodes that vote: those frames wait for, and this one (whose silhouettes, refused, no longer
  // make it one of them after a while: two nodes, one silent, could then never move).
  int live = 0, with_it = 0;
  int64_t oldest_with_it = frame_id;
  for (const auto& [name, n] : nodes_) {
    if (&n != &node && !awaited(n)) continue;
    ++live;
    if (n.newest_frame >= 0 && near(n.newest_frame, frame_id)) {
      ++with_it;
      oldest_with_it = std::min(oldest_with_it, n.newest_frame);
    }
  }
  if (2 * with_it <= live) {
    if (!node.told_frame_id) {
      node.told_frame_id = true;
      spdlog::warn(
          "node {}: silhouettes of frame {}, {} frames from the newest the studio has seen ({}): "
          "not used unless most nodes' frame ids move there too",
          node.report.name, frame_id, frame_id - newest_seen_, newest_seen_);
    }
    followLoneNode(node, frame_id);
    return false;
  }
  spdlog::warn("the cameras' frame ids moved from {} to {} on {} of {} nodes: following them",
               newest_seen_, frame_id, with_it, live);
  // The frames in flight belong to the old count; the poses still being fitted for them find no
  // frame to go to.
  for (auto it = frames_.begin(); it != frames_.end();) {
    if (counting_) ++frames_overtaken_;
    it = retireFrame(it);
  }
  refused_.fill(-1);
  newest_done_ = oldest_with_it - 1;
  newest_seen_ = frame_id;
  for (auto& [name, n] : nodes_) n.told_frame_id = false;
  return true;
}

int64_t StudioCoordinator::idArrivingAt(int64_t arrived_ns) const {
  const std::pair<int64_t, int64_t>*oldest = nullptr, *newest = nullptr, *nearest = nullptr;
  for (const auto& instant : instants_) {
    if (instant.first < 0 || std::abs(instant.first - newest_seen_) > kInstants) continue;
    if (!oldest || instant.first < oldest->first) oldest = &instant;
    if (!newest || instant.first > newest->first) newest = &instant;
    if (!nearest || std::abs(instant.second - arrived_ns) < std::abs(nearest->second - arrived_ns))
      nearest = &instant;
  }
  if (!nearest || newest->first - oldest->first < kInstants / 4) return -1;
  const double period =
      double(newest->second - oldest->second) / double(newest->first - oldest->first);
  if (period <= 0) return -1;
  const double frames = double(arrived_ns - nearest->second) / period;
  const double whole = std::round(frames);
  if (std::abs(frames - whole) > 0.25 || std::abs(whole) > kInstants) return -1;
  return nearest->first + int64_t(whole);
}

void StudioCoordinator::followLoneNode(NodeState& node, int64_t frame_id) {
  const int64_t now = node.last_ns;
  if (node.refused_since_ns == 0) node.refused_since_ns = now;
  // Its silhouettes of an instant come its usual lag behind the first of that instant's.
  const int64_t id = idArrivingAt(now - node.lag_ns);
  const int64_t shift = id >= 0 ? id - frame_id : 0;
  node.agreeing = shift != 0 && shift == node.suggested_shift ? node.agreeing + 1 : 0;
  node.suggested_shift = shift;
  const int64_t wait = std::chrono::nanoseconds(kFollowAfter).count();
  if (node.agreeing < kAgreeing || now - node.refused_since_ns < wait ||
      now - node.frame_ids_told_ns < wait || node.peer.empty() || node.times_told > kTimesTold)
    return;
  node.frame_ids_told_ns = now;
  if (++node.times_told > kTimesTold) {  // it keeps its ids (a recording's, an older node)
    spdlog::warn(
        "node {}: its frame ids stay {} from the other nodes' after being told {} times: "
        "not told again; its cameras are left out until they meet",
        node.report.name, shift, kTimesTold);
    return;
  }
  Message message;
  message.sender = "studio";
  message.sent_ns = steadyNowNs();
  message.body = FrameIdsData{shift};
  spdlog::warn(
      "node {}: its frame ids lie {} from the other nodes' for the same instants (its cameras "
      "restarted alone?): told to move them",
      node.report.name, shift);
  endpoint_.send(node.peer, encoder_.encode(message), std::chrono::milliseconds(5));
}

void StudioCoordinator::FrameState::clearForReuse() {
  first_ns = captured_ns = pose_sent_ns = offsets_sent_ns = offsets_out_ns = 0;
  std::fill(node_bytes.begin(), node_bytes.end(), 0);
  views.clear();
  mocap_begun = false;
  silhouettes.clear();
  silhouette_nodes.clear();
  pose_nodes.clear();
  statistics_nodes.clear();
  pose = PoseData();
  refine_sum.vertex_count = 0;  // reset() when the first node's statistics arrive
  image_nodes.clear();
  for (auto& [view, blender] : blends) blender.reset(blender.width(), blender.height());
}

StudioCoordinator::FrameState& StudioCoordinator::frameState(int64_t frame_id) {
  const auto it = frames_.find(frame_id);
  if (it != frames_.end()) return it->second;
  if (spare_frames_.empty()) return frames_[frame_id];
  auto node = std::move(spare_frames_.back());
  spare_frames_.pop_back();
  node.key() = frame_id;
  return frames_.insert(std::move(node)).position->second;
}

std::map<int64_t, StudioCoordinator::FrameState>::iterator StudioCoordinator::retireFrame(
    std::map<int64_t, FrameState>::iterator it) {
  const auto next = std::next(it);
  auto node = frames_.extract(it);
  // As many as are in flight at once (four at most with the default admission), and a few more.
  if (spare_frames_.size() < 8) {
    node.mapped().clearForReuse();
    spare_frames_.push_back(std::move(node));
  }
  return next;
}

void StudioCoordinator::beginMocap(int64_t frame_id, FrameState& frame) {
  int begun = 0;
  bool newer_begun = false;
  for (const auto& [id, f] : frames_) {
    begun += f.mocap_begun;
    newer_begun = newer_begun || (id > frame_id && f.mocap_begun);
  }
  // A frame whose deadline came after a newer frame began (it waited for a late node) is dropped:
  // fitted after the newer one, it would run the tracker's prediction backwards, or push the
  // newer one out of the tracker's queue.
  if (newer_begun ||
      (options_.max_frames_in_flight > 0 && begun >= options_.max_frames_in_flight)) {
    if (counting_) ++frames_refused_;
    retireFrame(frames_.find(frame_id));                     // the callers hold no iterator to it
    refused_[next_refused_++ % refused_.size()] = frame_id;  // its late silhouettes are ignored
    return;
  }
  if (counting_) peak_frames_begun_ = std::max(peak_frames_begun_, begun + 1);
  frame.mocap_begun = true;
  MocapJob job;
  if (!spare_jobs_.empty()) {
    job = std::move(spare_jobs_.back());
    spare_jobs_.pop_back();
  }
  job.frame_id = frame_id;
  std::swap(job.silhouettes, frame.silhouettes);  // the frame keeps the job's buffers meanwhile
  // A frame still waiting for the tracker is pushed out by this one, and dropped.
  if (std::optional<MocapJob> stale = mocap_jobs_.push(std::move(job))) {
    if (const auto it = frames_.find(stale->frame_id); it != frames_.end()) {
      if (counting_) ++frames_overtaken_;
      retireFrame(it);
      refused_[next_refused_++ % refused_.size()] = stale->frame_id;  // late silhouettes too
    }
    stale->silhouettes.clear();
    spare_jobs_.push_back(std::move(*stale));
  }
}

void StudioCoordinator::mocapLoop() {
  std::vector<const LowResSilhouette*> all;
  while (!mocap_jobs_.closed()) {
    std::optional<MocapJob> next = mocap_jobs_.pop(std::chrono::milliseconds(100));
    if (!next || mocap_jobs_.closed()) continue;
    MocapJob& job = *next;
    const int64_t start = steadyNowNs();
    all.clear();
    for (const LowResSilhouette& s : job.silhouettes) all.push_back(&s);
    const TrackResult* tracked = nullptr;
    if (tracker_) {
      // A fit that throws (a body model it cannot use, numbers gone bad) must not end the thread,
      // and with it the studio: the frame goes on with the placed generic human, the tracker
      // starts again, and the log says why (once for each new reason).
      try {
        tracked = &tracker_->track(all);
      } catch (const std::exception& e) {
        if (mocap_error_ != e.what()) {
          mocap_error_ = e.what();
          spdlog::error("motion capture: {}; the actor is looked for again", mocap_error_);
        }
        tracker_->reset();
      }
    }
    if (tracked && tracked->valid()) {
      // The tracked angles on the nodes' generic human, scaled to the actor (posed_body.h).
      job.pose =
          poseMessageFor(*generic_skeleton_, tracker_->skeleton(), tracked->pose, tracked->joints);
    } else {
      // Nobody tracked: the generic human standing where the hull is, in its rest pose.
      const ActorLocation where = locator_.locate(all);
      job.pose = PoseData();
      job.pose.root[0] = float(where.found ? where.centroid.x() : 0.0);
      job.pose.root[1] = float(where.found ? where.centroid.y() : 0.0);
      job.pose.root[2] = 0.0f;
      job.pose.angles.assign(size_t(3) * joints_, 0.0f);
    }
    job.ms = (steadyNowNs() - start) / 1e6;
    mocap_done_.push(std::move(job));
    mocap_ready_.notify();
  }
}

void StudioCoordinator::takePoses() {
  mocap_ready_.clear();
  while (std::optional<MocapJob> done = mocap_done_.pop(std::chrono::milliseconds(0))) {
    MocapJob& job = *done;
    last_pose_ = job.pose;
    last_pose_frame_ = job.frame_id;
    if (counting_) mocap_ms_.add(job.ms);
    const auto it = frames_.find(job.frame_id);
    if (it != frames_.end()) {
      FrameState& frame = it->second;
      std::swap(frame.silhouettes, job.silhouettes);
      frame.pose = job.pose;
      sendPose(job.frame_id, frame);
    }
    job.silhouettes.clear();
    spare_jobs_.push_back(std::move(job));
  }
}

void StudioCoordinator::sendPose(int64_t frame_id, FrameState& frame) {
  // Before the pose, the views to render it for, encoded into buffers kept from frame to frame.
  while (view_encoders_.size() < views_.size())
    view_encoders_.push_back(std::make_unique<MessageEncoder>());
  view_bytes_.clear();
  for (size_t v = 0; v < views_.size(); ++v) {
    view_message_.sender = "studio";
    view_message_.frame_id = frame_id;
    view_message_.sent_ns = steadyNowNs();
    view_message_.body = views_[v];  // the same alternative: its vectors keep their memory
    view_bytes_.push_back(view_encoders_[v]->encode(view_message_));
  }
  Message message;
  message.sender = "studio";
  message.frame_id = frame_id;
  message.sent_ns = steadyNowNs();
  message.body = frame.pose;
  const std::span<const uint8_t> bytes = encoder_.encode(message);
  frame.views.clear();
  for (const ViewData& view : views_) frame.views.push_back({view.view, view.width, view.height});
  for (auto& [name, node] : nodes_) {
    if (!awaited(node) || node.peer.empty()) continue;
    bool sent = true;
    for (const std::span<const uint8_t> v : view_bytes_)
      sent = sent && endpoint_.send(node.peer, v, std::chrono::milliseconds(5));
    if (sent && endpoint_.send(node.peer, bytes, std::chrono::milliseconds(5)))
      frame.pose_nodes.insert(name);
  }
  frame.pose_sent_ns = steadyNowNs();
  sentAt(frame_id) = {frame_id, frame.pose_sent_ns, 0};
  if (frame.pose_nodes.empty()) finishFrame(frame_id, frame);
}

void StudioCoordinator::runRefinement(int64_t frame_id, FrameState& frame) {
  const int64_t start = steadyNowNs();
  frame.offsets_sent_ns = start;
  RefinementStatistics& sum = frame.refine_sum;
  if (sum.vertex_count == 0) {  // no node's statistics: nothing to refine or render
    finishFrame(frame_id, frame);
    return;
  }
  sum.dropOutside();
  // The statistics are of the body's vertices, or of them and their window points.
  const int vertices = refinedVertices(sum.vertex_count);
  if (!refiner_ || refiner_->config().offset_count != sum.offset_count ||
      refiner_->dataErrors().size() != size_t(vertices) * sum.offset_count) {
    refiner_ = std::make_unique<MeshRefiner>(
        options_.refine, vertices,
        bodyFits(vertices) ? options_.body->rest.triangles : std::vector<Eigen::Vector3i>{});
  }
  // The offsets go straight into the message, which is kept from frame to frame: its vectors
  // keep their memory.
  Message& message = offsets_message_;
  if (!std::holds_alternative<OffsetsData>(message.body)) message.body = OffsetsData{};
  OffsetsData& offsets = std::get<OffsetsData>(message.body);
  if (!refiner_->refine(sum, offsets.offsets)) {
    finishFrame(frame_id, frame);
    return;
  }
  const int64_t refined = steadyNowNs();
  offsets.offset_count = refiner_->config().offsetLevels();
  offsets.visibility.clear();
  // Which cameras see each vertex of the mesh the nodes will render: posed and refined as they
  // will, from the same pose message and offsets.
  if (bodyFits(vertices)) {
    posedBodyMesh(*options_.body, frame.pose, body_pose_, body_transforms_, posed_positions_,
                  posed_normals_);
    applyOffsets(options_.refine, offsets.offsets, posed_positions_, posed_normals_,
                 refined_positions_);
    const LumigraphParams lumigraph;  // the nodes' renderers'
    visibility_.compute(rig_, refined_positions_, options_.body->rest.triangles,
                        lumigraph.depth_map_divisor, lumigraph.depth_tolerance_m);
    offsets.visibility.assign(visibility_.masks().begin(), visibility_.masks().end());
  }
  message.sender = "studio";
  message.frame_id = frame_id;
  message.sent_ns = steadyNowNs();
  const std::span<const uint8_t> bytes = encoder_.encode(message);
  if (counting_) {
    refine_ms_.add((refined - start) / 1e6);
    visibility_ms_.add((steadyNowNs() - refined) / 1e6);
  }
  int sent = 0;
  frame.offsets_out_ns = steadyNowNs();
  if (SentAt& at = sentAt(frame_id); at.frame_id == frame_id) at.offsets_ns = frame.offsets_out_ns;
  for (const std::string& name : frame.statistics_nodes) {
    NodeState& node = nodes_.at(name);
    if (node.report.lost || node.peer.empty()) continue;
    sent += endpoint_.send(node.peer, bytes, std::chrono::milliseconds(5));
  }
  if (sent == 0) finishFrame(frame_id, frame);
}

void StudioCoordinator::finishFrame(int64_t frame_id, FrameState& frame) {
  const int64_t now = steadyNowNs();
  const int64_t start = now;
  // Hull agreement at the posed vertices (offset 0): the share seen by some camera and outside
  // none of their silhouettes.
  int agreeing = 0, seen_vertices = 0;
  const RefinementStatistics& sum = frame.refine_sum;
  const int vertices = refinedVertices(sum.vertex_count);  // the vertices, not window points
  const int zero = options_.refine.zeroOffsetIndex();
  for (int v = 0; v < vertices; ++v) {
    const size_t s = size_t(v) * sum.offset_count + zero;
    if (sum.colour_count[s] == 0 && sum.outside[s] == 0) continue;
    ++seen_vertices;
    agreeing += sum.outside[s] == 0;
  }
  const int64_t combined = steadyNowNs();
  // Whole: every node still awaited sent its image of every view. A frame without some (a node
  // that missed a deadline) lacks what only that node's cameras saw, the director's view full of
  // holes: it is shown only when no whole frame was for hold_incomplete (a node that never makes
  // it in time would otherwise leave the view frozen), else dropped.
  bool whole = !frame.views.empty(), drawn = false;
  for (size_t v = 0; v < frame.views.size() && whole; ++v) {
    const auto it = frame.image_nodes.find(frame.views[v][0]);
    for (const auto& [name, node] : nodes_) {
      if (awaited(node) && (it == frame.image_nodes.end() || !it->second.count(name))) {
        whole = false;
        break;
      }
    }
  }
  for (const auto& [view, blender] : frame.blends) drawn = drawn || blender.added() > 0;
  const bool hold =
      drawn && !whole && last_whole_ns_ > 0 &&
      now - last_whole_ns_ < std::chrono::nanoseconds(options_.hold_incomplete).count();
  const bool shown = drawn && !hold;
  for (const auto& [view, blender] : frame.blends) {
    if (!shown) break;
    if (blender.added() == 0) continue;
    // Normalise the nodes' alphas per pixel and blend.
    BlendedImage& image = last_images_[view];
    image.frame_id = frame_id;
    image.pose = frame.pose;
    image.width = blender.width();
    image.height = blender.height();
    blender.finish(image.rgba);
    if (blended_sink_) blended_sink_(view, image);
  }

  // A run asked for max_frames counts exactly those: frames that complete together (several are
  // in flight) beyond it are still shown, not counted. A frame that no node's image reached (their
  // statistics or images missed the deadlines, as while the nodes start or on an overloaded
  // machine) shows nothing: it is dropped, not done, so that a run of N frames shows N.
  if (shown && whole) last_whole_ns_ = now;
  if (drawn) incomplete_share_ = 0.9 * incomplete_share_ + 0.1 * double(!whole);
  updateDeadlines();
  if (counting_ && !shown && (options_.max_frames == 0 || frames_done_ < options_.max_frames)) {
    ++frames_unshown_;
    frames_held_ += hold;
  } else if (counting_ && (options_.max_frames == 0 || frames_done_ < options_.max_frames)) {
    combine_ms_.add((combined - start) / 1e6);
    blend_ms_.add((steadyNowNs() - combined) / 1e6);
    if (frame.pose_sent_ns > 0) statistics_wait_ms_.add((now - frame.pose_sent_ns) / 1e6);
    if (seen_vertices > 0) hull_agreement_sum_ += double(agreeing) / seen_vertices;
    // From the capture to the image shown, both on the wall clock (the nodes may be other PCs).
    // Beyond a minute either way the clocks are not in step: the latency is not measured, and the
    // log says why once.
    const double latency_ms = (wallNowNs() - frame.captured_ns) / 1e6;
    if (latency_ms >= 0 && latency_ms < 60'000) {
      latencies_ms_.add(latency_ms);
      if (timeline_.size() < kTimelineFrames) timeline_.emplace_back(now, float(latency_ms));
    } else if (!told_clocks_) {
      told_clocks_ = true;
      spdlog::warn(
          "frame {}: captured {:.0f} s from the studio's clock: the nodes' PCs and the studio's do "
          "not keep the same time (run chrony or PTP on them); the latency is not measured",
          frame_id, -latency_ms / 1000);
    }
    ++frames_done_;
    frames_incomplete_ += !whole;
    if (start_ns_ == 0) start_ns_ = now;
    last_done_ns_ = now;
    recent_done_ns_.add(double(now));
    for (auto& [name, node] : nodes_) {
      if (!node.report.lost && !frame.silhouette_nodes.count(name)) ++node.report.frames_missed;
      if (node.index >= 0 && size_t(node.index) < frame.node_bytes.size() &&
          frame.node_bytes[node.index] > 0) {
        node.shown_bytes += frame.node_bytes[node.index];
        ++node.shown_frames;
      }
    }
  }
  // Older frames still open will never be shown: they are dropped.
  for (auto it = frames_.begin(); it != frames_.end() && it->first <= frame_id;) {
    if (it->first < frame_id && counting_) ++frames_overtaken_;
    it = retireFrame(it);
  }
  newest_done_ = frame_id;
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
  r.hull_agreement = frames_done_ > 0 ? hull_agreement_sum_ / frames_done_ : 0;
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
