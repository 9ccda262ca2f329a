#include "core/body/skinned_mesh.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace lumistage {

void TriangleMesh::computeNormals() {
  computeVertexNormals(positions, triangles, normals);
}

void computeVertexNormals(const Eigen::Matrix3Xf& positions,
                          const std::vector<Eigen::Vector3i>& triangles,
                          Eigen::Matrix3Xf& normals) {
  normals.setZero(3, positions.cols());
  for (const Eigen::Vector3i& t : triangles) {
    const Eigen::Vector3f a = positions.col(t[0]), b = positions.col(t[1]), c = positions.col(t[2]);
    const Eigen::Vector3f n = (b - a).cross(c - a);  // length = twice the area: area weighting
    for (int k = 0; k < 3; ++k) normals.col(t[k]) += n;
  }
  for (int i = 0; i < normals.cols(); ++i) {
    const float length = normals.col(i).norm();
    if (length > 0) normals.col(i) /= length;
  }
}

void SkinnedMesh::validate() const {
  const size_t n = static_cast<size_t>(rest.positions.cols());
  if (static_cast<size_t>(rest.normals.cols()) != n || skin.joints.size() != n ||
      skin.weights.size() != n) {
    throw std::invalid_argument("skinned mesh: " + std::to_string(n) + " vertices but " +
                                std::to_string(rest.normals.cols()) + " normals, " +
                                std::to_string(skin.joints.size()) + " joint sets and " +
                                std::to_string(skin.weights.size()) + " weight sets");
  }
  if (!materials.empty() && materials.size() != n) {
    throw std::invalid_argument("skinned mesh: materials do not match the vertex count");
  }
  for (size_t v = 0; v < n; ++v) {
    // A NaN or an absurd coordinate (a broken export) would reach the tracker's calibration and
    // the nodes' depth maps.
    const Eigen::Vector3f p = rest.positions.col(Eigen::Index(v));
    if (!p.allFinite() || p.cwiseAbs().maxCoeff() > 100.0f) {
      throw std::invalid_argument("skinned mesh: vertex " + std::to_string(v) + " is at (" +
                                  std::to_string(p.x()) + ", " + std::to_string(p.y()) + ", " +
                                  std::to_string(p.z()) + "): expected metres within 100 m");
    }
    if (!rest.normals.col(Eigen::Index(v)).allFinite()) {
      throw std::invalid_argument("skinned mesh: vertex " + std::to_string(v) +
                                  " has a normal that is not a number");
    }
    float sum = 0;
    for (int k = 0; k < kMaxInfluences; ++k) {
      if (skin.joints[v][k] >= skeleton.jointCount()) {
        throw std::invalid_argument("skinned mesh: vertex " + std::to_string(v) +
                                    " refers to joint " + std::to_string(skin.joints[v][k]) +
                                    " of " + std::to_string(skeleton.jointCount()));
      }
      if (!(skin.weights[v][k] >= 0) || !std::isfinite(skin.weights[v][k])) {
        throw std::invalid_argument("skinned mesh: vertex " + std::to_string(v) +
                                    " has a weight of " + std::to_string(skin.weights[v][k]) +
                                    ": expected a number from 0 to 1");
      }
      sum += skin.weights[v][k];
    }
    if (std::abs(sum - 1.0f) > 1e-3f) {
      throw std::invalid_argument("skinned mesh: weights of vertex " + std::to_string(v) +
                                  " sum to " + std::to_string(sum) + ", expected 1");
    }
  }
  for (const Eigen::Vector3i& t : rest.triangles) {
    if ((t.array() < 0).any() || (t.array() >= static_cast<int>(n)).any()) {
      throw std::invalid_argument("skinned mesh: a triangle refers to a vertex out of range");
    }
  }
}

void skinMesh(const SkinnedMesh& mesh, const std::vector<Eigen::Affine3f>& transforms,
              Eigen::Matrix3Xf& positions, Eigen::Matrix3Xf& normals) {
  const Eigen::Index n = mesh.rest.positions.cols();
  if (positions.cols() != n) positions.resize(3, n);
  if (normals.cols() != n) normals.resize(3, n);
  for (Eigen::Index v = 0; v < n; ++v) {
    const auto& joints = mesh.skin.joints[v];
    const auto& weights = mesh.skin.weights[v];
    Eigen::Matrix<float, 3, 4> blended = weights[0] * transforms[joints[0]].matrix().topRows<3>();
    for (int k = 1; k < kMaxInfluences; ++k) {
      if (weights[k] > 0) blended += weights[k] * transforms[joints[k]].matrix().topRows<3>();
    }
    positions.col(v) = blended.leftCols<3>() * mesh.rest.positions.col(v) + blended.col(3);
    // The blended linear part is close to a rotation; its normal transform is the inverse
    // transpose, which for LBS blends is well approximated by the blend itself, renormalised.
    normals.col(v) = (blended.leftCols<3>() * mesh.rest.normals.col(v)).normalized();
  }
}

Status checkClosedManifold(const TriangleMesh& mesh) {
  std::unordered_map<uint64_t, int> directed;  // (a, b) -> count
  auto key = [](uint32_t a, uint32_t b) { return (uint64_t(a) << 32) | b; };
  for (const Eigen::Vector3i& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) ++directed[key(t[k], t[(k + 1) % 3])];
  }
  std::string problems;
  int count = 0;
  for (const auto& [edge, n] : directed) {
    const uint32_t a = uint32_t(edge >> 32), b = uint32_t(edge & 0xffffffffu);
    auto reverse = directed.find(key(b, a));
    const int m = reverse == directed.end() ? 0 : reverse->second;
    if (n != 1 || m != 1) {
      if (++count <= 3) {
        problems += "edge " + std::to_string(a) + "-" + std::to_string(b) + " used " +
                    std::to_string(n) + " time(s) this way and " + std::to_string(m) +
                    " the other; ";
      }
    }
  }
  if (count == 0) return {};
  return Status::failure(problems + std::to_string(count) + " bad edge(s) in all");
}

}  // namespace lumistage
