#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

#include "core/base/status.h"
#include "core/body/skeleton.h"

namespace lumistage {

// A triangle mesh. Floats: meshes go to the GPU and a few mm of precision is plenty.
struct TriangleMesh {
  Eigen::Matrix3Xf positions;              // metres
  Eigen::Matrix3Xf normals;                // unit, outward
  std::vector<Eigen::Vector3i> triangles;  // counter-clockwise seen from outside

  int vertexCount() const { return static_cast<int>(positions.cols()); }
  // Area-weighted vertex normals from the triangles.
  void computeNormals();
};

// The same for any positions and triangles; `normals` is resized only when its size differs.
void computeVertexNormals(const Eigen::Matrix3Xf& positions,
                          const std::vector<Eigen::Vector3i>& triangles, Eigen::Matrix3Xf& normals);

constexpr int kMaxInfluences = 4;

// Up to four joints move each vertex; unused slots have weight 0 (and joint 0).
struct SkinWeights {
  std::vector<std::array<uint16_t, kMaxInfluences>> joints;
  std::vector<std::array<float, kMaxInfluences>> weights;  // sum to 1
};

// A mesh bound to a skeleton in its rest pose: what linear blend skinning poses.
struct SkinnedMesh {
  Skeleton skeleton;
  TriangleMesh rest;
  SkinWeights skin;
  // Optional per-vertex material index (the virtual studio's actor uses it for its surface).
  std::vector<uint8_t> materials;

  // Throws std::invalid_argument when sizes disagree, a joint index is out of range, or a
  // vertex's weights are negative or do not sum to 1 (within 1e-3).
  void validate() const;
};

// Linear blend skinning of positions and normals: p = Σ w_j M_j p_rest, n = normalize(Σ w_j R_j
// n_rest). `transforms` from Skeleton::skinningTransforms. Outputs are resized only when their
// size differs: reuse them and the call does not allocate.
void skinMesh(const SkinnedMesh& mesh, const std::vector<Eigen::Affine3f>& transforms,
              Eigen::Matrix3Xf& positions, Eigen::Matrix3Xf& normals);

// Checks that a mesh is closed and manifold: every edge is used by exactly two triangles, once in
// each direction. Fails saying what is wrong (the first few edges) when it is not.
Status checkClosedManifold(const TriangleMesh& mesh);

}  // namespace lumistage
