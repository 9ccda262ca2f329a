// A camera node's views (CameraNode, camera_node.h): the posed body kept per frame, the partial
// images rendered with the refined offsets, and the views kept for the frames to come.
#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>

#include "core/net/posed_body.h"
#include "core/pipeline/camera_node.h"
#include "core/refine/mesh_refiner.h"

namespace lumistage {

CameraNode::Posed& CameraNode::keepPosed(int64_t frame_id) {
  if (const auto it = posed_.find(frame_id); it != posed_.end()) return it->second;
  if (spare_posed_.empty()) return posed_[frame_id];
  auto node = std::move(spare_posed_.back());
  spare_posed_.pop_back();
  node.key() = frame_id;
  return posed_.insert(std::move(node)).position->second;
}

void CameraNode::releasePosedUpTo(int64_t frame_id) {
  while (!posed_.empty() && posed_.begin()->first <= frame_id) {
    auto node = posed_.extract(posed_.begin());
    node.mapped().set.reset();
    spare_posed_.push_back(std::move(node));
  }
}

std::vector<Message> CameraNode::partialImagesWithOffsets(const Message& message) {
  const auto it = posed_.find(message.frame_id);
  if (it == posed_.end()) return {};  // too old: dropped already
  const OffsetsData& offsets = std::get<OffsetsData>(message.body);
  Posed& posed = it->second;
  const std::shared_ptr<const Set> set = posed.set;
  const Eigen::Vector3d pivot = posed.pivot;
  // Offsets for another mesh or configuration are ignored, and said once.
  const bool fits = offsets.offsets.size() == size_t(posed.positions.cols()) &&
                    offsets.offset_count == options_.refine.offsetLevels();
  if (!fits && !told_offsets_) {
    told_offsets_ = true;
    spdlog::warn(
        "node {}: frame {}: the studio's offsets are for {} vertices at {} levels, this node "
        "refines {} at {}: not used; are the studio's refine: configuration and body another?",
        name_, message.frame_id, offsets.offsets.size(), offsets.offset_count,
        posed.positions.cols(), options_.refine.offsetLevels());
  }
  if (fits) {
    surface_levels_.assign(offsets.offsets.begin(), offsets.offsets.end());
    surface_frame_ = message.frame_id;
    applyOffsets(options_.refine, offsets.offsets, posed.positions, posed.normals, positions_);
    // The refined surface's own normals (the lumigraph's facing term and rim dilation): 0.1 dB
    // of leave-one-out over the posed mesh's.
    computeVertexNormals(positions_, body_.rest.triangles, normals_);
  }
  releasePosedUpTo(message.frame_id);  // this frame and older ones are done with
  if (!fits || !set) return {};
  {
    std::lock_guard lock(view_mutex_);
    const auto frame = frame_views_.find(message.frame_id);
    if (frame != frame_views_.end()) {
      const FrameViews& kept = frame->second;
      render_views_.resize(kept.count);
      for (size_t v = 0; v < kept.count; ++v) render_views_[v] = kept.views[v];  // keep memory
    } else {  // none came with this frame's pose (a studio of an older version): the latest
      render_views_.clear();
      for (const auto& [id, view] : views_) render_views_.push_back(view);
    }
  }
  return partialImagesFor(*set, message.frame_id, render_views_, pivot, offsets.visibility);
}

void CameraNode::keepView(int64_t frame_id, const ViewData& view) {
  // Ids far below the newest kept: the cameras restarted, and the old frames' views go.
  if (!frame_views_.empty() && frame_id < frame_views_.rbegin()->first - kFrameIdWindow) {
    while (!frame_views_.empty())
      spare_frame_views_.push_back(frame_views_.extract(frame_views_.begin()));
  }
  auto it = frame_views_.find(frame_id);
  if (it == frame_views_.end()) {
    if (spare_frame_views_.empty()) {
      it = frame_views_.emplace(frame_id, FrameViews()).first;
    } else {
      auto node = std::move(spare_frame_views_.back());
      spare_frame_views_.pop_back();
      node.key() = frame_id;
      node.mapped().count = 0;  // its views' memory kept for the assignments below
      it = frame_views_.insert(std::move(node)).position;
    }
  }
  FrameViews& kept = it->second;
  const auto end = kept.views.begin() + static_cast<std::ptrdiff_t>(kept.count);
  const auto same =
      std::find_if(kept.views.begin(), end, [&](const ViewData& v) { return v.view == view.view; });
  if (same != end) {
    *same = view;
  } else if (kept.count < kept.views.size()) {
    kept.views[kept.count++] = view;
  } else {
    kept.views.push_back(view);
    ++kept.count;
  }
  while (static_cast<int>(frame_views_.size()) > 2 * options_.frames_kept)
    spare_frame_views_.push_back(frame_views_.extract(frame_views_.begin()));
}

}  // namespace lumistage
