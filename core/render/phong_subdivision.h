#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "core/render/topology_key.h"
#include "core/render/vertex_visibility.h"

namespace lumistage {

// One step of Phong tessellation (Boubekeur & Alexa 2008) on the CPU, for rendering a coarse mesh
// as the curved surface its vertices and normals describe: each edge gets a vertex at its middle,
// lifted toward the tangent planes of its two ends, and each triangle becomes four. The flat
// triangles of the 1930-vertex generic human cut inside a limb by up to 3 mm between vertices; the
// texture each camera projects onto them then lands off the surface by as much (docs/lumigraph.md).
// A middle's normal is its ends' normals averaged; its visibility mask is its ends' masks ANDed: a
// camera sees the middle of an edge when it sees both ends. Vertices keep their indices (the
// middles follow them), so per-vertex data of the coarse mesh stays valid. The edge table is
// rebuilt only when the triangles change; after the first mesh of a size, nothing allocates.
class PhongSubdivision {
 public:
  // 0: the middles stay on the flat edges; 1: full Phong. 0.75, the authors' choice, was the one
  // of 0.5, 0.75 and 1 that gained on the reference walk both over the actor's mask and over the
  // matte (docs/lumigraph.md).
  static constexpr float kShape = 0.75f;

  // Triangles with an index outside `positions` are left out. `masks` may be empty (masks() then
  // is).
  void subdivide(const Eigen::Matrix3Xf& positions, const Eigen::Matrix3Xf& normals,
                 std::span<const Eigen::Vector3i> triangles,
                 std::span<const CameraMask> masks = {});

  const Eigen::Matrix3Xf& positions() const { return positions_; }
  const Eigen::Matrix3Xf& normals() const { return normals_; }
  const std::vector<Eigen::Vector3i>& triangles() const { return triangles_; }
  const std::vector<CameraMask>& masks() const { return masks_; }

 private:
  void buildTopology(int vertex_count, std::span<const Eigen::Vector3i> triangles);

  TopologyKey built_for_;               // the triangles the topology was built for
  std::vector<Eigen::Vector2i> edges_;  // middle k is vertex vertex_count + k
  Eigen::Matrix3Xf positions_, normals_;
  std::vector<Eigen::Vector3i> triangles_;
  std::vector<CameraMask> masks_;
};

}  // namespace lumistage
