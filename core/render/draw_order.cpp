#include "core/render/draw_order.h"

#include <deque>

namespace lumistage {

bool DrawOrder::build(int n, std::span<const Eigen::Vector3i> triangles) {
  if (!built_for_.changed(n, triangles)) return false;
  // Each vertex's triangles (compressed rows).
  std::vector<int> first(size_t(n) + 1, 0), used;
  const int count = static_cast<int>(triangles.size());
  std::vector<uint8_t> valid(count, 0);
  for (int t = 0; t < count; ++t) {
    const Eigen::Vector3i& tri = triangles[t];
    if (tri.minCoeff() < 0 || tri.maxCoeff() >= n) continue;
    valid[t] = 1;
    for (int k = 0; k < 3; ++k) ++first[tri[k] + 1];
  }
  for (int v = 0; v < n; ++v) first[v + 1] += first[v];
  used.resize(first[n]);
  std::vector<int> fill(first.begin(), first.end() - 1);
  for (int t = 0; t < count; ++t)
    if (valid[t])
      for (int k = 0; k < 3; ++k) used[fill[triangles[t][k]]++] = t;

  // Patches grown breadth-first; the next patch starts beside the last (from the triangles the
  // last one reached but did not take), else at the first triangle left.
  std::vector<uint8_t> taken(count, 0);
  std::vector<int> sequence;
  sequence.reserve(count);
  std::deque<int> frontier, queue;
  int next_seed = 0;
  while (true) {
    int seed = -1;
    while (!frontier.empty() && seed < 0) {
      if (!taken[frontier.front()]) seed = frontier.front();
      frontier.pop_front();
    }
    while (seed < 0 && next_seed < count) {
      if (valid[next_seed] && !taken[next_seed]) seed = next_seed;
      ++next_seed;
    }
    if (seed < 0) break;
    queue.clear();
    queue.push_back(seed);
    taken[seed] = 1;
    int in_patch = 0;
    while (!queue.empty() && in_patch < kPatch) {
      const int t = queue.front();
      queue.pop_front();
      sequence.push_back(t);
      ++in_patch;
      for (int k = 0; k < 3; ++k) {
        const int v = triangles[t][k];
        for (int i = first[v]; i < first[v + 1]; ++i) {
          const int u = used[i];
          if (taken[u]) continue;
          taken[u] = 1;
          queue.push_back(u);
        }
      }
    }
    // Reached but not drawn: free again, and where the next patch begins.
    for (int t : queue) {
      taken[t] = 0;
      frontier.push_back(t);
    }
  }
  // Vertices numbered by first use.
  std::vector<int> number(n, -1);
  order_.clear();
  order_.reserve(n);
  triangles_.clear();
  triangles_.reserve(sequence.size());
  for (int t : sequence) {
    Eigen::Vector3i out;
    for (int k = 0; k < 3; ++k) {
      int& id = number[triangles[t][k]];
      if (id < 0) {
        id = static_cast<int>(order_.size());
        order_.push_back(triangles[t][k]);
      }
      out[k] = id;
    }
    triangles_.push_back(out);
  }
  for (int v = 0; v < n; ++v)
    if (number[v] < 0) order_.push_back(v);
  return true;
}

}  // namespace lumistage
