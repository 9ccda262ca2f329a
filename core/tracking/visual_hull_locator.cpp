#include "core/tracking/visual_hull_locator.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "core/geometry/stage_volume.h"

namespace lumistage {

VisualHullLocator::VisualHullLocator(const Rig& rig, int silhouette_step, double voxel_m,
                                     std::optional<StageBox> stage)
    : cameras_(rig.cameraCount()), step_(silhouette_step), voxel_m_(voxel_m) {
  const StageBox box = stage ? *stage : stageVolume(rig);
  lower_ = box.lower;
  dims_ = (box.size() / voxel_m).array().ceil().cast<int>();
  const size_t voxels = size_t(dims_.x()) * dims_.y() * dims_.z();
  // Its cells and the voxels' centres (projected a camera at a time, for all voxels at once).
  const size_t bytes = voxels * (cameras_ * sizeof(int32_t) + 3 * sizeof(double) +
                                 2 * sizeof(double) + sizeof(double));
  if (bytes > kMaxBytes) {
    throw std::invalid_argument(fmt::format(
        "the stage box ({}) at {} cm voxels needs {} MB to locate the actor with {} cameras, more "
        "than {} MB: give the rig file a smaller `stage` (docs/rig-file.md)",
        describeStage(box), 100 * voxel_m, bytes >> 20, cameras_, kMaxBytes >> 20));
  }
  cell_.assign(voxels * cameras_, -1);
  Eigen::Matrix3Xd centres(3, voxels);
  for (int z = 0; z < dims_.z(); ++z) {
    for (int y = 0; y < dims_.y(); ++y) {
      for (int x = 0; x < dims_.x(); ++x) {
        centres.col((size_t(z) * dims_.y() + y) * dims_.x() + x) =
            lower_ + voxel_m * Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5);
      }
    }
  }
  Eigen::Matrix2Xd pixels;
  Eigen::VectorXd depths;
  for (int c = 0; c < cameras_; ++c) {
    const Camera& camera = rig.camera(c);
    camera.project(centres, pixels, depths);
    const int w = camera.width() / step_, h = camera.height() / step_;
    for (size_t v = 0; v < voxels; ++v) {
      if (depths(v) <= 0) continue;
      const int x = static_cast<int>(std::floor(pixels(0, v) / step_)),
                y = static_cast<int>(std::floor(pixels(1, v) / step_));
      if (x >= 0 && y >= 0 && x < w && y < h) cell_[v * cameras_ + c] = y * w + x;
    }
  }
}

int VisualHullLocator::byCamera(const std::vector<const LowResSilhouette*>& silhouettes,
                                std::vector<const LowResSilhouette*>& by_camera) const {
  by_camera.assign(size_t(cameras_), nullptr);
  int present = 0;
  for (const LowResSilhouette* s : silhouettes) {
    if (s && s->camera >= 0 && s->camera < cameras_ && s->step == step_) {
      by_camera[s->camera] = s;
      ++present;
    }
  }
  return present;
}

Eigen::Vector3d VisualHullLocator::centre(size_t v) const {
  const int x = int(v % dims_.x()), y = int((v / dims_.x()) % dims_.y()),
            z = int(v / (size_t(dims_.x()) * dims_.y()));
  return lower_ + voxel_m_ * Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5);
}

ActorLocation VisualHullLocator::locate(
    const std::vector<const LowResSilhouette*>& silhouettes) const {
  std::vector<const LowResSilhouette*> by_camera;
  ActorLocation out;
  out.voxel_m = voxel_m_;
  if (byCamera(silhouettes, by_camera) < 2) return out;
  const size_t voxels = voxelCount();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (size_t v = 0; v < voxels; ++v) {
    if (!keeps(v, by_camera)) continue;
    const Eigen::Vector3d p = centre(v);
    if (out.voxels == 0) out.lower = out.upper = p;
    out.lower = out.lower.cwiseMin(p);
    out.upper = out.upper.cwiseMax(p);
    sum += p;
    ++out.voxels;
  }
  out.found = out.voxels > 0;
  if (out.found) out.centroid = sum / out.voxels;
  return out;
}

void VisualHullLocator::carve(const std::vector<const LowResSilhouette*>& silhouettes,
                              std::vector<uint32_t>& kept) const {
  kept.clear();
  std::vector<const LowResSilhouette*> by_camera;
  if (byCamera(silhouettes, by_camera) < 2) return;
  const size_t voxels = voxelCount();
  for (size_t v = 0; v < voxels; ++v)
    if (keeps(v, by_camera)) kept.push_back(uint32_t(v));
}

}  // namespace lumistage
