#include "core/pipeline/camera_node.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <thread>

#include "core/base/error.h"
#include "core/pipeline/pipeline.h"
#include "core/refine/mesh_refiner.h"
#include "core/render/lumigraph_weights.h"

namespace lumistage {

CameraNode::CameraNode(const Rig& rig, const std::string& name, std::unique_ptr<FrameSource> source,
                       NodeEndpointConfig endpoint, SkinnedMesh body, CameraNodeOptions options)
    : rig_(rig),
      name_(name),
      source_(std::move(source)),
      endpoint_(std::move(endpoint)),
      body_(std::move(body)),
      options_(options),
      sampler_(options.refine) {
  const std::optional<int> node = rig_.findNode(name_);
  if (!node) throw Error("camera node: no node '" + name_ + "' in the rig");
  cameras_ = rig_.nodes()[*node].cameras;
  keyers_.resize(cameras_.size());
}

Message CameraNode::silhouettesOf(const Set& set) const {
  SilhouettesData silhouettes;
  LowResSilhouette s;
  for (size_t k = 0; k < cameras_.size(); ++k) {
    computeSilhouette(keyers_[k], set.frames[k].image.view(), cameras_[k], options_.silhouette_step,
                      s);
    silhouettes.masks.push_back({s.camera, s.width, s.height, std::move(s.bits)});
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
  Pose pose = Pose::rest(body_.skeleton.jointCount());
  pose.root_translation_m =
      Eigen::Vector3d(pose_data.root[0], pose_data.root[1], pose_data.root[2]);
  for (int j = 0;
       j < body_.skeleton.jointCount() && 3 * j + 2 < static_cast<int>(pose_data.angles.size());
       ++j) {
    pose.angles_rad[j] = Eigen::Vector3d(pose_data.angles[3 * j], pose_data.angles[3 * j + 1],
                                         pose_data.angles[3 * j + 2]);
  }
  body_.skeleton.skinningTransforms(pose, transforms_);
  skinMesh(body_, transforms_, positions_, normals_);

  // The refinement's samples: every vertex's offsets along its normal in this node's cameras.
  sampler_cameras_.resize(cameras_.size());
  for (size_t k = 0; k < cameras_.size(); ++k) {
    sampler_cameras_[k] = {&rig_.camera(cameras_[k]), set->frames[k].image.view(), &keyers_[k],
                           nullptr};
  }
  sampler_.sample(sampler_cameras_, positions_, normals_, body_.rest.triangles, refine_stats_);
  VertexStatisticsData stats;
  stats.vertex_count = static_cast<uint32_t>(positions_.cols());
  stats.offset_count = options_.refine.offset_count;
  encodeRefinementStatistics(refine_stats_, stats.packed);
  // Kept until the studio's offsets for the frame arrive.
  Posed& posed = posed_[message.frame_id];
  posed.set = set;
  posed.positions = positions_;
  posed.normals = normals_;
  while (static_cast<int>(posed_.size()) > options_.frames_kept) posed_.erase(posed_.begin());
  Message reply;
  reply.frame_id = message.frame_id;
  reply.sent_ns = steadyNowNs();
  reply.body = std::move(stats);
  return reply;
}

Message CameraNode::partialImageFor(const Set& set, int64_t frame_id, const ViewData& view) {
  const int w = view.width, h = view.height;
  Eigen::Matrix3f R;
  for (int i = 0; i < 9; ++i) R(i / 3, i % 3) = view.rotation[i];
  const Eigen::Vector3f t(view.translation[0], view.translation[1], view.translation[2]);
  const Eigen::Vector3d desired = (-R.transpose() * t).cast<double>();
  // Weights over every camera of the rig (the nodes agree on them), applied to our own.
  std::vector<Eigen::Vector3d> centres;
  for (const Camera& c : rig_.cameras()) centres.push_back(c.centre());
  std::vector<char> own(rig_.cameraCount(), 0);
  for (int c : cameras_) own[c] = 1;
  LumigraphWeightParams params;
  params.epsilon_rad = 0.05;  // bounds a weight by 20, so alpha fits a byte
  const float alpha_scale = 255.0f / float(20 * params.k);
  std::vector<float> depth(size_t(w) * h, 1e30f);
  std::vector<uint8_t> rgba(size_t(w) * h * 4, 0);
  std::vector<double> weights;
  std::unique_ptr<bool[]> visible(new bool[rig_.cameraCount()]);
  std::vector<std::optional<Eigen::Vector2d>> pixels(rig_.cameraCount());  // of the vertex
  const int n = static_cast<int>(positions_.cols());
  for (int v = 0; v < n; ++v) {
    const Eigen::Vector3f p = positions_.col(v), nrm = normals_.col(v);
    const Eigen::Vector3f pc = R * p + t;
    if (pc.z() <= 0.05f) continue;
    const int x = static_cast<int>(view.fx * pc.x() / pc.z() + view.cx + 0.5f);
    const int y = static_cast<int>(view.fy * pc.y() / pc.z() + view.cy + 0.5f);
    if (x < 1 || y < 1 || x >= w - 1 || y >= h - 1) continue;
    // Which cameras see the vertex on their image (occlusion: with the depth maps of refinement).
    for (int c = 0; c < rig_.cameraCount(); ++c) {
      pixels[c] = rig_.camera(c).project(p.cast<double>());
      visible[c] = pixels[c] && rig_.camera(c).inImage(*pixels[c]);
    }
    lumigraphWeights(p.cast<double>(), nrm.cast<double>(), desired, centres,
                     std::span<const bool>(visible.get(), rig_.cameraCount()), params, weights);
    double sum = 0, colour[3] = {0, 0, 0};
    for (size_t k = 0; k < cameras_.size(); ++k) {
      const int c = cameras_[k];
      if (weights[c] <= 0) continue;
      const Eigen::Vector2d& px = *pixels[c];
      const Rgb rgb = colourAt(set.frames[k].image.view(), static_cast<int>(px.x() + 0.5),
                               static_cast<int>(px.y() + 0.5));
      colour[0] += weights[c] * rgb.r, colour[1] += weights[c] * rgb.g,
          colour[2] += weights[c] * rgb.b;
      sum += weights[c];
    }
    if (sum <= 0) continue;
    const uint8_t out[4] = {uint8_t(colour[0] / sum), uint8_t(colour[1] / sum),
                            uint8_t(colour[2] / sum),
                            uint8_t(std::clamp(float(sum) * alpha_scale, 1.0f, 255.0f))};
    for (int dy = -1; dy <= 1; ++dy) {  // a 3x3 splat: the surface is sampled at its vertices
      for (int dx = -1; dx <= 1; ++dx) {
        const size_t i = size_t(y + dy) * w + (x + dx);
        if (pc.z() >= depth[i]) continue;
        depth[i] = pc.z();
        std::memcpy(&rgba[4 * i], out, 4);
      }
    }
  }
  PartialImageData image;
  image.view = view.view;
  image.width = w;
  image.height = h;
  image.encoding = ImageEncoding::kRleRgba;
  image.data = encodeRleRgba(rgba);
  Message message;
  message.frame_id = frame_id;
  message.sent_ns = steadyNowNs();
  message.body = std::move(image);
  return message;
}

void CameraNode::captureLoop(const std::atomic<bool>& stop) {
  // Frames arrive camera by camera; a set is complete when all own cameras are in.
  std::map<int64_t, std::shared_ptr<Set>> assembling;
  CameraFrame frame;
  while (!stop) {
    bool got = false;
    {
      std::lock_guard lock(source_mutex_);
      if (source_->finished()) break;
      got = source_->next(frame, std::chrono::milliseconds(5));
    }
    if (!got) continue;
    const auto k = std::find(cameras_.begin(), cameras_.end(), frame.camera) - cameras_.begin();
    if (k >= static_cast<long>(cameras_.size())) continue;
    std::shared_ptr<Set>& set = assembling[frame.frame_id];
    if (!set) {
      set = std::make_shared<Set>();
      set->frame_id = frame.frame_id;
      set->frames.resize(cameras_.size());
    }
    std::swap(set->frames[k], frame);
    int complete = 0;
    for (const CameraFrame& f : set->frames) complete += f.frame_id == set->frame_id;
    if (complete == static_cast<int>(cameras_.size())) {
      set->captured_ns = steadyNowNs();
      sets_.push(set);
      assembling.erase(set->frame_id);
    }
    while (assembling.size() > 4) assembling.erase(assembling.begin());  // a camera fell behind
  }
  source_finished_ = true;
}

void CameraNode::silhouetteLoop(const std::atomic<bool>& stop) {
  while (!stop) {
    std::optional<std::shared_ptr<const Set>> set = sets_.pop(std::chrono::milliseconds(20));
    if (!set) continue;
    {
      std::lock_guard lock(kept_mutex_);
      kept_[(*set)->frame_id] = *set;
      while (static_cast<int>(kept_.size()) > options_.frames_kept) kept_.erase(kept_.begin());
    }
    Message silhouettes = silhouettesOf(**set);
    {
      std::lock_guard lock(monitor_mutex_);
      monitor_set_ = *set;
      monitor_silhouettes_ = std::get<SilhouettesData>(silhouettes.body).masks;
    }
    outbox_.push(std::move(silhouettes));
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
    std::lock_guard lock(source_mutex_);
    for (int c : cameras_) state.stats.push_back(source_->stats(c));
  }
  state.sets_sent = sets_sent_;
  state.bytes_sent = bytes_sent_;
  return state;
}

void CameraNode::statisticsLoop(const std::atomic<bool>& stop) {
  while (!stop) {
    while (std::optional<Message> offsets = offsets_.pop(std::chrono::milliseconds(0))) {
      if (std::optional<Message> image = partialImageWithOffsets(*offsets))
        outbox_.push(std::move(*image));
    }
    std::optional<Message> pose = poses_.pop(std::chrono::milliseconds(2));
    if (!pose) continue;
    std::optional<Message> reply = statisticsFor(*pose);
    if (!reply) continue;
    outbox_.push(std::move(*reply));
  }
}

std::optional<Message> CameraNode::partialImageWithOffsets(const Message& message) {
  const auto it = posed_.find(message.frame_id);
  if (it == posed_.end()) return std::nullopt;  // too old: dropped already
  const OffsetsData& offsets = std::get<OffsetsData>(message.body);
  Posed posed = std::move(it->second);
  posed_.erase(posed_.begin(), std::next(it));
  if (offsets.offsets.size() != size_t(posed.positions.cols()) ||
      offsets.offset_count != options_.refine.offset_count) {
    return std::nullopt;  // for another mesh or configuration
  }
  applyOffsets(options_.refine, offsets.offsets, posed.positions, posed.normals, positions_);
  normals_ = posed.normals;
  std::optional<ViewData> view;
  {
    std::lock_guard lock(view_mutex_);
    view = view_;
  }
  if (!view || !posed.set) return std::nullopt;
  return partialImageFor(*posed.set, message.frame_id, *view);
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

void CameraNode::run(const std::atomic<bool>& stop) {
  std::atomic<bool> stop_workers{false};
  std::thread capture([&] { captureLoop(stop_workers); });
  std::thread silhouettes([&] { silhouetteLoop(stop_workers); });
  std::thread statistics([&] { statisticsLoop(stop_workers); });
  auto last_heartbeat = std::chrono::steady_clock::now() - options_.heartbeat;
  while (!stop && !source_finished_) {
    while (std::optional<Message> out = outbox_.pop(std::chrono::milliseconds(0)))
      send(std::move(*out));
    if (std::optional<DecodeResult> received = endpoint_.receive(std::chrono::milliseconds(2))) {
      if (received->ok() && std::holds_alternative<PoseData>(received->message->body)) {
        poses_.push(std::move(*received->message));
      } else if (received->ok() && std::holds_alternative<OffsetsData>(received->message->body)) {
        offsets_.push(std::move(*received->message));
      } else if (received->ok() && std::holds_alternative<ViewData>(received->message->body)) {
        std::lock_guard lock(view_mutex_);
        view_ = std::get<ViewData>(received->message->body);
      }
    }
    const auto now = std::chrono::steady_clock::now();
    if (now - last_heartbeat >= options_.heartbeat) {
      last_heartbeat = now;
      HeartbeatData heartbeat;
      {
        std::lock_guard lock(source_mutex_);
        for (int c : cameras_) {
          const CameraStats s = source_->stats(c);
          heartbeat.cameras.push_back(
              {rig_.camera(c).name(), s.frames, s.dropped, float(s.frame_rate_hz), s.last_error});
        }
      }
      heartbeat.bytes_sent = bytes_sent_;
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
