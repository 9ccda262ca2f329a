#include "core/refine/mesh_refiner.h"

#include <algorithm>
#include <cmath>

namespace lumistage {

MeshRefiner::MeshRefiner(const RefineConfig& config, int vertex_count,
                         const std::vector<Eigen::Vector3i>& triangles)
    : config_(config), vertex_count_(vertex_count) {
  // Neighbours: vertices sharing an edge, each once.
  std::vector<std::vector<int>> adjacency(vertex_count);
  for (const Eigen::Vector3i& t : triangles) {
    for (int e = 0; e < 3; ++e) {
      const int a = t[e], b = t[(e + 1) % 3];
      if (a < 0 || b < 0 || a >= vertex_count || b >= vertex_count) continue;
      adjacency[a].push_back(b);
      adjacency[b].push_back(a);
    }
  }
  neighbour_start_.assign(vertex_count + 1, 0);
  for (int v = 0; v < vertex_count; ++v) {
    std::sort(adjacency[v].begin(), adjacency[v].end());
    adjacency[v].erase(std::unique(adjacency[v].begin(), adjacency[v].end()), adjacency[v].end());
    neighbour_start_[v + 1] = neighbour_start_[v] + static_cast<int>(adjacency[v].size());
    neighbours_.insert(neighbours_.end(), adjacency[v].begin(), adjacency[v].end());
  }
  const size_t samples = size_t(vertex_count) * config_.offset_count;
  data_.assign(samples, 0);
  total_.assign(config_.offset_count, 0);
  offsets_m_.resize(config_.offset_count);
  for (int i = 0; i < config_.offset_count; ++i) offsets_m_[i] = float(config_.offsetAt(i));
  // The outward term at each offset: on a camera's contour, then off it.
  outward_.resize(2 * size_t(config_.offset_count));
  for (int i = 0; i < config_.offset_count; ++i) {
    const float t_rel = config_.t_max_m > 0 ? offsets_m_[i] / float(config_.t_max_m) : 0.0f;
    outward_[i] = -float(config_.outward_weight) * t_rel;
    outward_[config_.offset_count + i] = -float(config_.off_contour_outward_weight) * t_rel;
  }
  previous_.assign(vertex_count, uint8_t(config_.zeroOffsetIndex()));
  current_.assign(vertex_count, uint8_t(config_.zeroOffsetIndex()));
}

namespace {

// The colour term of one point's sample: its variance over the cameras (n - 1: two cameras
// agreeing by chance is weaker evidence than four), averaged over the channels, in units of the
// statistics' colour bits², through v / (v + sigma²). The caller checks that two cameras or more
// see it inside the hull.
inline float pointColour(const RefinementStatistics& stats, size_t s, float sigma2) {
  const int n = stats.colour_count[s];
  const float r = stats.sums[3 * s], g = stats.sums[3 * s + 1], b = stats.sums[3 * s + 2];
  const float variance = std::max(
      0.0f, (float(stats.squares[s]) - (r * r + g * g + b * b) / float(n)) / (3.0f * float(n - 1)));
  return variance / (variance + sigma2);
}

}  // namespace

float MeshRefiner::windowColour(const RefinementStatistics& stats, size_t s, int points,
                                size_t window, float sigma2) {
  float sum = pointColour(stats, s, sigma2), count = 1;
  for (int p = 1; p < points; ++p) {
    const size_t q = s + size_t(p) * window;
    if (stats.outside[q] > 0 || stats.colour_count[q] < 2) continue;
    sum += pointColour(stats, q, sigma2);
    count += 1;
  }
  return sum / count;
}

int MeshRefiner::windowPoints(const RefinementStatistics& stats) const {
  if (stats.offset_count != config_.offset_count) return 0;
  if (stats.vertex_count == vertex_count_) return 1;
  if (vertex_count_ > 0 && stats.vertex_count == RefineConfig::kWindowPoints * vertex_count_)
    return RefineConfig::kWindowPoints;
  return 0;
}

bool MeshRefiner::onContour(const RefinementStatistics& stats, int v) {
  return size_t(v) < stats.contour.size() && stats.contour[v];
}

float MeshRefiner::dataError(const RefinementStatistics& stats, size_t s, int i) const {
  const int v = int(s / size_t(config_.offset_count));
  const bool contour = onContour(stats, v);
  float colour;
  if (stats.outside[s] > 0) {
    colour = 1.0f;
  } else if (stats.colour_count[s] < 2) {
    colour = float(config_.unseen_colour);
  } else {
    const float unit = float(1 << (8 - stats.colour_bits));
    const float sigma2 = float(config_.colour_sigma * config_.colour_sigma) / (unit * unit);
    const size_t window = size_t(vertex_count_) * config_.offset_count;
    colour = windowColour(stats, s, windowPoints(stats), window, sigma2);
  }
  const float bonus = contour && lastInside(stats, v) == i ? float(config_.contour_weight) : 0.0f;
  const float outward = outward_[(contour ? 0 : size_t(config_.offset_count)) + size_t(i)];
  return float(config_.outside_weight) * float(stats.outside[s]) + outward +
         float(config_.colour_weight) * colour - bonus;
}

int MeshRefiner::lastInside(const RefinementStatistics& stats, int v) const {
  const size_t first = size_t(v) * config_.offset_count;
  for (int i = config_.offset_count - 2; i >= 0; --i)
    if (stats.leavesHull(first + i)) return i;
  return -1;
}

int MeshRefiner::choose(const float* e) const {
  // The paper's fourth term: of the local minima within tie_margin of the lowest, the one closest
  // to t = 0.
  const int m = config_.offset_count;
  float lowest = e[0];
  for (int i = 1; i < m; ++i) lowest = std::min(lowest, e[i]);
  const float limit = lowest + float(config_.tie_margin);
  const int zero = config_.zeroOffsetIndex();
  int best = -1;
  for (int i = 0; i < m; ++i) {
    if (e[i] > limit) continue;
    const bool local = (i == 0 || e[i] <= e[i - 1]) && (i == m - 1 || e[i] <= e[i + 1]);
    if (!local) continue;
    if (best < 0 || std::abs(i - zero) < std::abs(best - zero)) best = i;
  }
  return best < 0 ? zero : best;
}

bool MeshRefiner::refine(const RefinementStatistics& stats, std::vector<uint8_t>& offsets) {
  const int m = config_.offset_count;
  const int points = windowPoints(stats);
  if (points == 0) return false;
  // The data terms (as dataError(), inlined for speed: every sample every frame).
  const float outside_w = float(config_.outside_weight), colour_w = float(config_.colour_weight);
  const float unseen = colour_w * float(config_.unseen_colour);
  const float unit = float(1 << (8 - stats.colour_bits));
  const float sigma2 = float(config_.colour_sigma * config_.colour_sigma) / (unit * unit);
  const size_t samples = size_t(vertex_count_) * m;
  for (int v = 0; v < vertex_count_; ++v) {
    const float* outward = &outward_[onContour(stats, v) ? 0 : m];
    for (size_t i = 0, s = size_t(v) * m; i < size_t(m); ++i, ++s) {
      float e = outward[i];
      if (stats.outside[s] > 0) {
        e += outside_w * float(stats.outside[s]) + colour_w;
      } else if (stats.colour_count[s] < 2) {
        e += unseen;
      } else {
        e += colour_w * windowColour(stats, s, points, samples, sigma2);
      }
      data_[s] = e;
    }
  }
  // The contour term: at a vertex on a camera's contour, the last sample inside the hull.
  const float contour_w =
      stats.contour.size() >= size_t(vertex_count_) ? float(config_.contour_weight) : 0.0f;
  for (int v = 0; contour_w > 0 && v < vertex_count_; ++v) {
    if (!stats.contour[v]) continue;
    const int i = lastInside(stats, v);
    if (i >= 0) data_[size_t(v) * m + i] -= contour_w;
  }
  const float inv_t = config_.t_max_m > 0 ? 1.0f / float(config_.t_max_m) : 0.0f;
  const float temporal = has_previous_ ? float(config_.temporal_weight) : 0.0f;
  auto addTemporal = [&](int v, float* total) {
    if (temporal == 0) return;
    const float prev = offsets_m_[previous_[v]];
    for (int i = 0; i < m; ++i) {
      const float d = (offsets_m_[i] - prev) * inv_t;
      total[i] += temporal * d * d;
    }
  };
  float* total = total_.data();
  for (int v = 0; v < vertex_count_; ++v) {
    std::copy_n(&data_[size_t(v) * m], m, total);
    addTemporal(v, total);
    current_[v] = uint8_t(choose(total));
  }
  // Smoothness: iterated conditional modes, each vertex in turn against its neighbours' choices.
  const float smooth = float(config_.smoothWeightFor(vertex_count_));
  for (int sweep = 0; smooth > 0 && sweep < config_.smooth_iterations; ++sweep) {
    bool changed = false;
    for (int v = 0; v < vertex_count_; ++v) {
      const int begin = neighbour_start_[v], end = neighbour_start_[v + 1];
      if (begin == end) continue;
      std::copy_n(&data_[size_t(v) * m], m, total);
      addTemporal(v, total);
      // Σ_k (t - t_k)² = K t² - 2 t Σ t_k + Σ t_k²: one pass over the neighbours.
      float s1 = 0, s2 = 0;
      for (int k = begin; k < end; ++k) {
        const float tn = offsets_m_[current_[neighbours_[k]]] * inv_t;
        s1 += tn, s2 += tn * tn;
      }
      const float w = smooth / float(end - begin), count = float(end - begin);
      for (int i = 0; i < m; ++i) {
        const float t = offsets_m_[i] * inv_t;
        total[i] += w * (count * t * t - 2 * t * s1 + s2);
      }
      const uint8_t chosen = uint8_t(choose(total));
      changed = changed || chosen != current_[v];
      current_[v] = chosen;
    }
    if (!changed) break;
  }
  // Levels: where the chosen sample is inside the hull and its neighbour outward is outside, the
  // hull's surface lies between them, where the nodes located it below a pixel (the edges), or,
  // where none did, halfway (the unbiased guess: half a step, 2.5 mm by default, nearly a pixel at
  // 3 m, that the coverage of the silhouette would otherwise miss); halfway too where the inward
  // neighbour is outside (rare: between the legs). Elsewhere the vertex's data error around its
  // minimum is taken for a parabola through the chosen sample and its two neighbours: half a step
  // toward the side where the parabola's lowest point lies more than a quarter step away (a colour
  // minimum between two samples).
  constexpr int kPerStep = RefineConfig::kLevelsPerStep, kHalf = kPerStep / 2;
  if (offsets.size() != size_t(vertex_count_)) offsets.resize(vertex_count_);
  for (int v = 0; v < vertex_count_; ++v) {
    const int i = current_[v];
    const size_t s = size_t(v) * m + i;
    const uint8_t* outside = &stats.outside[size_t(v) * m];
    int level = kPerStep * i;
    if (outside[i] == 0) {
      if (i + 1 < m && outside[i + 1] > 0) {
        const int edge = stats.edges[s];
        level += edge == 0 ? kHalf
                           : (kPerStep * (edge - 1) + RefinementStatistics::kEdgeLevels / 2) /
                                 RefinementStatistics::kEdgeLevels;
      } else if (i > 0 && outside[i - 1] > 0) {
        level -= kHalf;
      } else if (i > 0 && i + 1 < m) {
        const float* d = &data_[s];
        const float curvature = d[-1] - 2 * d[0] + d[1];
        if (curvature > 0) {
          const float lowest = 0.5f * (d[-1] - d[1]) / curvature;  // in steps from sample i
          level += lowest > 0.25f ? kHalf : (lowest < -0.25f ? -kHalf : 0);
        }
      }
    }
    offsets[v] = uint8_t(level);
  }
  std::copy(current_.begin(), current_.end(), previous_.begin());
  has_previous_ = true;
  return true;
}

void applyOffsets(const RefineConfig& config, std::span<const uint8_t> offsets,
                  const Eigen::Matrix3Xf& positions, const Eigen::Matrix3Xf& normals,
                  Eigen::Matrix3Xf& out) {
  if (out.cols() != positions.cols()) out.resize(3, positions.cols());
  for (Eigen::Index v = 0; v < positions.cols(); ++v) {
    const int level = v < Eigen::Index(offsets.size()) ? offsets[v] : config.zeroLevel();
    out.col(v) = positions.col(v) + float(config.levelOffset(level)) * normals.col(v);
  }
}

}  // namespace lumistage
