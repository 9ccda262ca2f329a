#include "core/render/lumigraph_weights.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>

namespace lumistage {

namespace {

double angleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

double smoothstep(double edge0, double edge1, double x) {
  const double t = std::clamp((x - edge0) / (edge1 - edge0), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

}  // namespace

void lumigraphWeights(const Eigen::Vector3d& point, const Eigen::Vector3d& normal,
                      const Eigen::Vector3d& desired, std::span<const Eigen::Vector3d> cameras,
                      std::span<const bool> visible, const LumigraphWeightParams& params,
                      std::vector<double>& weights) {
  const size_t n = cameras.size();
  weights.assign(n, 0.0);
  const Eigen::Vector3d to_desired = desired - point;
  // Candidates: visible and facing the surface.
  thread_local std::vector<std::pair<double, size_t>> candidates;  // (angle, camera)
  thread_local std::vector<double> facing;
  candidates.clear();
  facing.assign(n, 0.0);
  for (size_t i = 0; i < n; ++i) {
    if (i >= visible.size() || !visible[i]) continue;
    const Eigen::Vector3d to_camera = cameras[i] - point;
    facing[i] = normal.dot(to_camera.normalized());
    if (facing[i] <= params.min_facing) continue;
    candidates.push_back({angleBetween(to_desired, to_camera), i});
  }
  if (candidates.empty()) return;
  const size_t k = std::min<size_t>(std::max(params.k, 1), candidates.size());
  std::partial_sort(candidates.begin(), candidates.begin() + std::min(k + 1, candidates.size()),
                    candidates.end());
  const double threshold = candidates.size() > k ? candidates[k].first : params.max_angle_rad;
  for (size_t j = 0; j < k; ++j) {
    const auto [angle, i] = candidates[j];
    const double a = std::max(angle, params.epsilon_rad);
    const double ramp = std::max(0.0, 1.0 - angle / std::max(threshold, params.epsilon_rad));
    weights[i] = ramp / a * smoothstep(params.min_facing, 1.0, facing[i]);
  }
  // When the k-th and (k+1)-th cameras tie, every kept weight is 0: fall back to the nearest.
  if (std::accumulate(weights.begin(), weights.end(), 0.0) == 0.0)
    weights[candidates[0].second] = 1.0;
}

}  // namespace lumistage
