#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "core/geometry/rig.h"
#include "core/imaging/silhouettes.h"

namespace lumistage {

// Where the actor is, from every camera's low-resolution silhouette: the stage's volume is
// carved on a coarse voxel grid (a voxel stays when every camera that sees it sees the actor
// there), and the kept voxels give the actor's centroid, extent and volume. Until the model-based
// tracker lands this places the generic skeleton; afterwards it initialises and re-finds the
// actor. Cost: voxels x cameras projections (a 6 cm grid of a 3x3x2.2 m stage, 12 cameras:
// ~1M projections, a few ms).
struct ActorLocation {
  bool found = false;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  // metres
  Eigen::Vector3d lower = Eigen::Vector3d::Zero(), upper = Eigen::Vector3d::Zero();
  int voxels = 0;
  double voxel_m = 0;
};

class VisualHullLocator {
 public:
  // Precomputes every voxel's cell in every camera (the rig does not move). `stage`: the box
  // searched; empty, the rig's (stageVolume). Throws std::invalid_argument, naming the box, when
  // that needs more than kMaxBytes.
  VisualHullLocator(const Rig& rig, int silhouette_step, double voxel_m = 0.06,
                    std::optional<StageBox> stage = {});
  static constexpr size_t kMaxBytes = size_t(256) << 20;

  // `silhouettes` may hold any subset of the cameras (a late node's are missing): cameras without
  // one do not carve. At least two cameras are needed to find anything.
  ActorLocation locate(const std::vector<const LowResSilhouette*>& silhouettes) const;

  // The hull itself, for analyses of the silhouettes (footage_sync.h): the voxels locate() keeps,
  // as indices (`kept` is reused), each voxel's cell in camera c's grid (y * width + x, -1 where
  // the camera does not see it) and its centre.
  void carve(const std::vector<const LowResSilhouette*>& silhouettes,
             std::vector<uint32_t>& kept) const;
  int32_t cell(size_t voxel, int camera) const { return cell_[voxel * cameras_ + camera]; }
  Eigen::Vector3d centre(size_t voxel) const;
  size_t voxelCount() const { return size_t(dims_.x()) * dims_.y() * dims_.z(); }

 private:
  // The silhouettes by camera index (null where missing or of another step); how many there are.
  int byCamera(const std::vector<const LowResSilhouette*>& silhouettes,
               std::vector<const LowResSilhouette*>& by_camera) const;
  // Whether voxel v is in the hull: at least two cameras see it, each of them the actor there.
  bool keeps(size_t v, const std::vector<const LowResSilhouette*>& by_camera) const {
    int seen = 0;
    for (int c = 0; c < cameras_; ++c) {
      const LowResSilhouette* s = by_camera[c];
      const int32_t cell = cell_[v * cameras_ + c];
      if (!s || cell < 0) continue;
      if (!s->at(cell % s->width, cell / s->width)) return false;
      ++seen;
    }
    return seen >= 2;
  }

  int cameras_;
  int step_;
  double voxel_m_;
  Eigen::Vector3d lower_;
  Eigen::Vector3i dims_;
  std::vector<int32_t>
      cell_;  // [voxel * cameras + camera]: y * width + x in the cell grid, -1: not seen
};

}  // namespace lumistage
