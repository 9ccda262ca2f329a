#pragma once

#include <Eigen/Core>
#include <span>
#include <vector>

#include "core/capture/image.h"
#include "core/geometry/camera.h"
#include "core/imaging/keyer.h"
#include "core/refine/depth_map.h"
#include "core/refine/refine_config.h"
#include "core/refine/refinement_statistics.h"

namespace lumistage {

// One camera's input to the sampler: its calibration, its image, and how to segment it — a green
// screen keyer, a background model learnt from the empty stage, or the frame's mask of the actor
// from another tool (at most one of the three; none: a default green screen keyer).
struct SamplerCamera {
  const Camera* camera = nullptr;
  ImageView image;
  const GreenScreenKeyer* green_screen = nullptr;
  const BackgroundModel* background = nullptr;
  const MaskKey* mask = nullptr;
};

// The tangent along which a vertex's window points lie (RefineConfig::window_points): the unit
// tangent of the plane normal to `normal` nearest the world's vertical (z), or, for a normal within
// 26 degrees of vertical, the one nearest x.
Eigen::Vector3f windowDirection(const Eigen::Vector3f& normal);

// The node's side of the refinement: for its own cameras, samples the images at every vertex's
// offsets along its normal and accumulates RefinementStatistics. With window points
// (RefineConfig::window_points = 3), the statistics hold 3n vertices: the n vertices, then the n
// points window_m along windowDirection() from them, then the n points window_m the other way,
// each sampled at the same offsets along its vertex's normal (with its vertex's normal and its own
// depth-map lookup) by the cameras that see it (the others count nothing for it, not even outside
// their silhouettes: a window point serves the colour term only). Segmentation is evaluated only at
// the sampled pixels; visibility comes from a low-resolution depth map of the posed mesh per
// camera (a vertex's visibility holds for all its offsets, as in the paper), or of the posed mesh
// moved by an earlier frame's offsets where the caller has them (`surface_levels`: nearer the
// actor). A green-screen camera's colours are despilled (RefineConfig::despill). A camera that keys
// almost none of the posed surface as the actor while the surface lies in its view (knocked toward
// the wall, its key broken) is left out (seesNobody()): every sample would be outside its
// silhouette and the hull term would carve the whole mesh away. After the first frame of a size,
// sample() does not allocate.
class RefinementSampler {
 public:
  explicit RefinementSampler(const RefineConfig& config) : config_(config) {}
  const RefineConfig& config() const { return config_; }

  // `positions` and `normals` (unit) of the posed mesh, `triangles` its faces. Overwrites `out`.
  // `surface_levels`: the refinement's offsets (RefineConfig levels) of the mesh's vertices from an
  // earlier frame, or empty (or of another size: ignored); with them, each camera's depth map, the
  // visibility tests and the contour marks are made on the posed mesh moved by them, at
  // RefineConfig::refined_depth_tolerance_m (the samples stay where they are).
  void sample(std::span<const SamplerCamera> cameras, const Eigen::Matrix3Xf& positions,
              const Eigen::Matrix3Xf& normals, const std::vector<Eigen::Vector3i>& triangles,
              RefinementStatistics& out, std::span<const uint8_t> surface_levels = {});

  // Per camera of the last sample() call, in its order: 1 where the camera keyed fewer than
  // kMinSurfaceSeen of the posed vertices in its view as the actor (at least kMinProbesInView in
  // view), and was left out.
  std::span<const uint8_t> seesNobody() const { return sees_nobody_; }
  static constexpr float kMinSurfaceSeen = 0.05f;
  static constexpr int kMinProbesInView = 16;

 private:
  // `surface_m`: each vertex's offset along its normal to the surface whose depth map `depth` is
  // (empty: the posed mesh's, at 0), looked up for a window point by its vertex.
  template <typename Key>
  void sampleCamera(const SamplerCamera& camera, const Key& key, const DepthMap& depth,
                    const Eigen::Matrix3Xf& positions, const Eigen::Matrix3Xf& normals,
                    std::span<const float> surface_m, RefinementStatistics& out) const;

  RefineConfig config_;
  std::vector<DepthMap> depth_maps_;
  std::vector<uint8_t> sees_nobody_;
  Eigen::Matrix3Xf window_positions_, window_normals_;  // the vertices and their window points
  std::vector<float> offsets_m_;
  // The surface of `surface_levels`: each vertex's offset, and the moved vertices.
  std::vector<float> surface_m_;
  Eigen::Matrix3Xf surface_positions_;
};

}  // namespace lumistage
