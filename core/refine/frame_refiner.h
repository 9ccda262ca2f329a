#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "core/capture/frame_source.h"
#include "core/geometry/rig.h"
#include "core/imaging/keyer.h"
#include "core/refine/mesh_refiner.h"
#include "core/refine/refinement_sampler.h"
#include "core/refine/refinement_statistics.h"

namespace lumistage {

// The whole refinement of one frame in one process, node by node as the distributed pipeline
// does it (each node samples its own cameras, its statistics go through the compressed wire form,
// the module combines and refines): for offline work on a session — evaluation, export. The
// green-screen keyers learn the screen from the first frame's images (a camera whose frame carries
// a mask from another tool, CameraFrame::mask, is keyed by it instead); from the second frame on,
// the nodes' visibility comes from the surface the frame before was refined to (as the nodes have
// the studio's offsets of an earlier frame), so frames are to be given in order.
class FrameRefiner {
 public:
  FrameRefiner(const Rig& rig, const RefineConfig& config, int vertex_count,
               const std::vector<Eigen::Vector3i>& triangles);

  // Refines the posed mesh (`positions`, `normals`) from a frame's images (indexed by rig
  // camera) into `refined`; camera `left_out` (>= 0), if any, is not sampled (the strict
  // leave-one-camera-out score). Throws Error if a node's statistics do not decode (a bug).
  void refine(const std::vector<CameraFrame>& frames, const Eigen::Matrix3Xf& positions,
              const Eigen::Matrix3Xf& normals, Eigen::Matrix3Xf& refined, int left_out = -1);

  // Each rig camera's clean plate (sessionPlates), which keys it instead of its green screen where
  // one is (a stage without a green screen); none: every camera on green.
  void setPlates(CameraPlates plates) { plates_ = std::move(plates); }

  // The last frame's offset levels (RefineConfig::offsetLevels()).
  const std::vector<uint8_t>& offsets() const { return offsets_; }
  // Compressed statistics of the last frame, summed over the nodes.
  size_t lastWireBytes() const { return wire_bytes_; }

 private:
  const Rig& rig_;
  RefineConfig config_;
  std::vector<Eigen::Vector3i> triangles_;
  RefinementSampler sampler_;
  MeshRefiner refiner_;
  std::vector<GreenScreenKeyer> keyers_;
  std::vector<MaskKey> mask_keys_;
  CameraPlates plates_;
  bool keyers_learnt_ = false;
  RefinementStatistics node_stats_, combined_;
  RefinementStatisticsCodec codec_;
  std::vector<uint8_t> wire_, offsets_;
  std::vector<SamplerCamera> inputs_;
  size_t wire_bytes_ = 0;
};

}  // namespace lumistage
