#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "core/refine/refine_config.h"
#include "core/refine/refinement_statistics.h"

namespace lumistage {

// The studio's refinement module (the paper's §IV): from the combined statistics of all nodes, the
// error of every vertex's every offset, and the offset each vertex takes (see RefineConfig for the
// terms). Smoothness between neighbouring vertices is solved by a few sweeps of iterated
// conditional modes from the per-vertex choice; temporal coherence pulls toward the previous
// frame's offsets. One object per mesh; refine() does not allocate.
class MeshRefiner {
 public:
  MeshRefiner(const RefineConfig& config, int vertex_count,
              const std::vector<Eigen::Vector3i>& triangles);
  const RefineConfig& config() const { return config_; }

  // Chooses an offset per vertex and writes its level (RefineConfig::offsetLevels():
  // kLevelsPerStep x the offset index, moved to the hull's edge where the silhouette crosses next
  // to it, or half a step where the error's parabola through its neighbours lies lowest more than
  // a quarter step away) to `offsets`, resized when its size differs. The statistics are of this
  // mesh's vertices, or of them and their window points (RefineConfig::kWindowPoints x the
  // vertices, RefinementSampler): a sample's colour term is then the mean over its points inside
  // the hull and seen by two cameras or more. Returns false (offsets untouched) when the
  // statistics' sizes are neither.
  bool refine(const RefinementStatistics& combined, std::vector<uint8_t>& offsets);
  // Forgets the previous frame (a cut, a new actor): the next frame has no temporal term.
  void resetTemporal() { has_previous_ = false; }

  // The data error of the last refine() (terms 1 to 3), per sample v·offset_count + t.
  const std::vector<float>& dataErrors() const { return data_; }
  // The data terms of one sample (of a vertex, not of a window point), for tests and tools. The
  // contour term counts at the vertex's last sample inside the hull, the outward term by whether
  // the vertex is on a contour.
  float dataError(const RefinementStatistics& stats, size_t sample, int offset_index) const;

 private:
  int choose(const float* error) const;
  // Vertex v's last sample inside the hull before it leaves outward (the contour term's), or -1.
  int lastInside(const RefinementStatistics& stats, int v) const;
  // Whether a camera sees vertex v on its contour (the contour term's and outward_weight's
  // vertices; off_contour_outward_weight at the others).
  static bool onContour(const RefinementStatistics& stats, int v);
  // 1 or RefineConfig::kWindowPoints (the statistics' points a vertex), 0 when they are not of
  // this mesh.
  int windowPoints(const RefinementStatistics& stats) const;
  // The colour term of vertex sample s averaged over its window's points (`window`: samples from
  // one point of a vertex to the next).
  static float windowColour(const RefinementStatistics& stats, size_t s, int points, size_t window,
                            float sigma2);

  RefineConfig config_;
  int vertex_count_;
  std::vector<int> neighbour_start_, neighbours_;  // CSR adjacency
  std::vector<float> data_, total_, offsets_m_;
  // The outward term at each offset (it depends on the config alone): offset_count values for the
  // vertices on a camera's contour, then offset_count for the others.
  std::vector<float> outward_;
  std::vector<uint8_t> previous_, current_;
  bool has_previous_ = false;
};

// The refined mesh: each vertex moved along its normal by its chosen offset level. `out` is resized
// only when its size differs.
void applyOffsets(const RefineConfig& config, std::span<const uint8_t> offsets,
                  const Eigen::Matrix3Xf& positions, const Eigen::Matrix3Xf& normals,
                  Eigen::Matrix3Xf& out);

}  // namespace lumistage
