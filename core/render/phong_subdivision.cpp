#include "core/render/phong_subdivision.h"

#include <algorithm>
#include <unordered_map>

namespace lumistage {

void PhongSubdivision::buildTopology(int n, std::span<const Eigen::Vector3i> triangles) {
  edges_.clear();
  triangles_.clear();
  std::unordered_map<uint64_t, int> middle;
  middle.reserve(triangles.size() * 2);
  const auto middleOf = [&](int a, int b) {
    const uint64_t key = (uint64_t(uint32_t(std::min(a, b))) << 32) | uint32_t(std::max(a, b));
    const auto [it, added] = middle.try_emplace(key, n + static_cast<int>(edges_.size()));
    if (added) edges_.emplace_back(a, b);
    return it->second;
  };
  for (const Eigen::Vector3i& t : triangles) {
    if (t.minCoeff() < 0 || t.maxCoeff() >= n) continue;
    const int ab = middleOf(t[0], t[1]), bc = middleOf(t[1], t[2]), ca = middleOf(t[2], t[0]);
    // Counter-clockwise as the coarse triangle.
    triangles_.emplace_back(t[0], ab, ca);
    triangles_.emplace_back(ab, t[1], bc);
    triangles_.emplace_back(ca, bc, t[2]);
    triangles_.emplace_back(ab, bc, ca);
  }
}

void PhongSubdivision::subdivide(const Eigen::Matrix3Xf& positions, const Eigen::Matrix3Xf& normals,
                                 std::span<const Eigen::Vector3i> triangles,
                                 std::span<const CameraMask> masks) {
  const int n = static_cast<int>(positions.cols());
  if (built_for_.changed(n, triangles)) buildTopology(n, triangles);
  const Eigen::Index total = n + static_cast<Eigen::Index>(edges_.size());
  if (positions_.cols() != total) positions_.resize(3, total);
  if (normals_.cols() != total) normals_.resize(3, total);
  positions_.leftCols(n) = positions;
  normals_.leftCols(n) = normals;
  for (size_t k = 0; k < edges_.size(); ++k) {
    const int a = edges_[k][0], b = edges_[k][1];
    const Eigen::Vector3f pa = positions.col(a), pb = positions.col(b);
    const Eigen::Vector3f na = normals.col(a), nb = normals.col(b);
    const Eigen::Vector3f m = 0.5f * (pa + pb);
    // The middle projected onto each end's tangent plane; their mean, blended with the middle.
    const Eigen::Vector3f onto_a = m - (m - pa).dot(na) * na, onto_b = m - (m - pb).dot(nb) * nb;
    positions_.col(n + Eigen::Index(k)) = (1 - kShape) * m + kShape * 0.5f * (onto_a + onto_b);
    const Eigen::Vector3f s = na + nb;
    const float length = s.norm();
    normals_.col(n + Eigen::Index(k)) = length > 1e-12f ? Eigen::Vector3f(s / length) : na;
  }
  if (masks.empty()) {
    masks_.clear();
    return;
  }
  masks_.resize(size_t(total));
  std::copy(masks.begin(), masks.begin() + std::min<size_t>(masks.size(), size_t(n)),
            masks_.begin());
  for (size_t k = 0; k < edges_.size(); ++k)
    masks_[size_t(n) + k] = masks_[size_t(edges_[k][0])] & masks_[size_t(edges_[k][1])];
}

}  // namespace lumistage
