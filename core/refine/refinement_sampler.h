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
// screen keyer or a background model learnt from the empty stage (exactly one of the two).
struct SamplerCamera {
  const Camera* camera = nullptr;
  ImageView image;
  const GreenScreenKeyer* green_screen = nullptr;
  const BackgroundModel* background = nullptr;
};

// The node's side of the refinement: for its own cameras, samples the images at every vertex's
// offsets along its normal and accumulates RefinementStatistics. Segmentation is evaluated only at
// the sampled pixels; visibility comes from a low-resolution depth map of the posed mesh per
// camera (a vertex's visibility holds for all its offsets, as in the paper). After the first
// frame of a size, sample() does not allocate.
class RefinementSampler {
 public:
  explicit RefinementSampler(const RefineConfig& config) : config_(config) {}
  const RefineConfig& config() const { return config_; }

  // `positions` and `normals` (unit) of the posed mesh, `triangles` its faces. Overwrites `out`.
  void sample(std::span<const SamplerCamera> cameras, const Eigen::Matrix3Xf& positions,
              const Eigen::Matrix3Xf& normals, const std::vector<Eigen::Vector3i>& triangles,
              RefinementStatistics& out);

  const DepthMap& depthMap(int k) const { return depth_maps_.at(k); }

 private:
  template <typename Key>
  void sampleCamera(const SamplerCamera& camera, const Key& key, const DepthMap& depth,
                    const Eigen::Matrix3Xf& positions, const Eigen::Matrix3Xf& normals,
                    RefinementStatistics& out) const;

  RefineConfig config_;
  std::vector<DepthMap> depth_maps_;
  std::vector<float> offsets_m_;
};

}  // namespace lumistage
