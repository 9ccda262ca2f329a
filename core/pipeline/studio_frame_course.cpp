// The studio coordinator's course of a frame (StudioCoordinator, studio_coordinator.h): its state,
// motion capture, the pose sent out, the refinement, and the frame finished and retired.
#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <utility>

#include "core/net/posed_body.h"
#include "core/pipeline/studio_coordinator.h"
#include "core/render/lumigraph_renderer.h"

namespace lumistage {

void StudioCoordinator::FrameState::clearForReuse() {
  first_ns = captured_ns = pose_sent_ns = offsets_sent_ns = offsets_out_ns = 0;
  std::fill(node_bytes.begin(), node_bytes.end(), 0);
  views.clear();
  mocap_begun = false;
  silhouettes.clear();
  colours.clear();
  silhouette_nodes.clear();
  pose_nodes.clear();
  statistics_nodes.clear();
  pose = PoseData();
  tracked = false;
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
  frame.admitted_ns = steadyNowNs();
  MocapJob job;
  if (!spare_jobs_.empty()) {
    job = std::move(spare_jobs_.back());
    spare_jobs_.pop_back();
  }
  job.frame_id = frame_id;
  std::swap(job.silhouettes, frame.silhouettes);  // the frame keeps the job's buffers meanwhile
  std::swap(job.colours, frame.colours);
  // A frame still waiting for the tracker is pushed out by this one, and dropped.
  if (std::optional<MocapJob> stale = mocap_jobs_.push(std::move(job))) {
    if (const auto it = frames_.find(stale->frame_id); it != frames_.end()) {
      if (counting_) ++frames_overtaken_;
      retireFrame(it);
      refused_[next_refused_++ % refused_.size()] = stale->frame_id;  // late silhouettes too
    }
    stale->silhouettes.clear();
    stale->colours.clear();
    spare_jobs_.push_back(std::move(*stale));
  }
}

void StudioCoordinator::mocapLoop() {
  std::vector<const LowResSilhouette*> all;
  // The cameras' colours on the cells' grid, for the tracker when it asks (kept from frame to
  // frame: a frame that carries colours allocates nothing once they have grown).
  std::vector<CellColours> dense;
  std::vector<const CellColours*> colours;
  while (!mocap_jobs_.closed()) {
    std::optional<MocapJob> next = mocap_jobs_.pop(std::chrono::milliseconds(100));
    if (!next || mocap_jobs_.closed()) continue;
    MocapJob& job = *next;
    const int64_t start = steadyNowNs();
    all.clear();
    for (const LowResSilhouette& s : job.silhouettes) all.push_back(&s);
    colours.clear();
    if (tracker_ && tracker_->wantsColours()) {
      dense.resize(std::max(dense.size(), job.silhouettes.size()));
      for (size_t k = 0; k < job.silhouettes.size() && k < job.colours.size(); ++k) {
        const std::vector<uint8_t>& sent = job.colours[k];
        if (!sent.empty() &&
            expandSilhouetteColours(job.silhouettes[k], sent.data(), sent.size(), dense[k]))
          colours.push_back(&dense[k]);
      }
    }
    const TrackResult* tracked = nullptr;
    if (tracker_) {
      // A fit that throws (a body model it cannot use, numbers gone bad) must not end the thread,
      // and with it the studio: the frame goes on with the placed generic human, the tracker
      // starts again, and the log says why (once for each new reason).
      try {
        tracked = &tracker_->track(all, colours);
      } catch (const std::exception& e) {
        if (mocap_error_ != e.what()) {
          mocap_error_ = e.what();
          spdlog::error("motion capture: {}; the actor is looked for again", mocap_error_);
        }
        tracker_->reset();
      }
    }
    job.tracked = tracked && tracked->valid();
    if (job.tracked) {
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
    job.start_ns = start;
    mocap_done_.push(std::move(job));
    mocap_ready_.notify();
  }
}

const std::vector<LowResSilhouette>* StudioCoordinator::silhouettesOf(int64_t frame_id) const {
  for (const auto& [frame, silhouettes] : kept_silhouettes_)
    if (frame == frame_id && frame_id >= 0) return &silhouettes;
  return nullptr;
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
      auto& kept = kept_silhouettes_[next_kept_silhouettes_];
      next_kept_silhouettes_ = (next_kept_silhouettes_ + 1) % kKeptSilhouettes;
      kept.first = job.frame_id;
      kept.second = frame.silhouettes;
      frame.pose = job.pose;
      frame.tracked = job.tracked;
      frame.mocap_start_ns = job.start_ns;
      frame.mocap_end_ns = job.start_ns + int64_t(job.ms * 1e6);
      sendPose(job.frame_id, frame);
    }
    job.silhouettes.clear();
    job.colours.clear();
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
  if (shown && shown_pose_sink_) shown_pose_sink_(frame_id, frame.pose, frame.tracked);

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
    frames_tracked_ += frame.tracked;
    // From the capture to the image shown, both on the wall clock (the nodes may be other PCs).
    // Beyond a minute either way the clocks are not in step: the latency is not measured, and the
    // log says why once.
    const double latency_ms = (wallNowNs() - frame.captured_ns) / 1e6;
    if (latency_ms >= 0 && latency_ms < 60'000) {
      latencies_ms_.add(latency_ms);
      addLatencyParts(frame, latency_ms, now, steadyNowNs());
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

void StudioCoordinator::addLatencyParts(const FrameState& frame, double latency_ms,
                                        int64_t finish_ns, int64_t now_ns) {
  const int64_t at[] = {frame.first_ns,       frame.admitted_ns,  frame.mocap_start_ns,
                        frame.mocap_end_ns,   frame.pose_sent_ns, frame.offsets_sent_ns,
                        frame.offsets_out_ns, finish_ns,          now_ns};
  static_assert(std::size(at) == kLatencyParts.size());
  for (const int64_t t : at)
    if (t <= 0) return;
  double studio_ms = 0;
  for (size_t i = 1; i < std::size(at); ++i) {
    const double ms = std::max<int64_t>(0, at[i] - at[i - 1]) / 1e6;
    latency_parts_ms_[i].add(ms);
    studio_ms += ms;
  }
  latency_parts_ms_[0].add(std::max(0.0, latency_ms - studio_ms));
}

}  // namespace lumistage
