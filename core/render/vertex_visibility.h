#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "core/geometry/rig.h"
#include "core/refine/depth_map.h"

namespace lumistage {

// Which cameras of a rig see each vertex of a mesh: bit c of a vertex's mask is set when camera
// c sees it, i.e. the vertex lies in front of the camera (more than 5 cm), projects inside its
// image and is not hidden: its depth is at most `tolerance_m` behind the camera's depth map of
// the mesh (front faces, rasterised on the CPU at 1/`divisor` of the camera's size, looked up at
// the nearest cell). The lumigraph's weights (docs/lumigraph.md) take these masks; the studio
// computes them once a frame for the refined mesh and sends them to every node, so that no node
// renders the rig's depth maps. At most 32 cameras (one 32-bit mask a vertex, CameraMask).
using CameraMask = uint32_t;

class VertexVisibility {
 public:
  static constexpr int kMaxCameras = 32;

  // Reuses its maps and masks: allocates only when the mesh or the rig grows. Throws Error for a
  // rig of more than kMaxCameras cameras.
  void compute(const Rig& rig, const Eigen::Matrix3Xf& positions,
               std::span<const Eigen::Vector3i> triangles, int divisor, float tolerance_m);

  // One mask a vertex of the last compute().
  std::span<const CameraMask> masks() const { return masks_; }

 private:
  std::vector<DepthMap> maps_;
  std::vector<CameraMask> masks_;
};

}  // namespace lumistage
