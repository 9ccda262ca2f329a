#pragma once

#include <Eigen/Core>
#include <span>
#include <vector>

#include "core/render/topology_key.h"

namespace lumistage {

// An order to draw a triangle mesh in so that each vertex is shaded about once. Mesa llvmpipe
// shades an indexed draw's vertices in batches, a vertex again in every batch that uses it: drawn
// in its own order, the generic human's vertices were shaded 1.25 times each, Phong-subdivided
// (the middles numbered after all the corners) 1.47 times, the 8234-vertex true surface 1.51
// times (a pipeline-statistics query of the vertex shader's invocations; docs/lumigraph.md). Here
// the triangles are drawn in compact patches of kPatch, each grown breadth-first over shared
// vertices from a triangle beside the patches before, and the vertices are numbered in the order
// the triangles first use them: 1.21, 1.27 and 1.28 times. A GPU's post-transform cache likes the
// same locality. Depends on the topology alone: built once for a mesh's triangles, then applied to
// every frame's vertices.
class DrawOrder {
 public:
  static constexpr int kPatch = 512;  // triangles; of 64 to 2048 tried, the fewest invocations

  // Triangles with an index outside [0, vertex_count) are left out. Rebuilt only when the
  // triangles or the vertex count differ from the last call's; returns whether it was.
  bool build(int vertex_count, std::span<const Eigen::Vector3i> triangles);

  // The draw's vertex k is the mesh's vertex order()[k]; vertices no triangle uses come last.
  const std::vector<int>& order() const { return order_; }
  // The triangles in drawing order, indexing the reordered vertices.
  const std::vector<Eigen::Vector3i>& triangles() const { return triangles_; }

 private:
  TopologyKey built_for_;
  std::vector<int> order_;
  std::vector<Eigen::Vector3i> triangles_;
};

}  // namespace lumistage
