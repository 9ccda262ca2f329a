// A head's crown below the hull's top (PoseTracker::Impl::crownBelowRaisedHands,
// pose_tracker_impl.h): an actor found with his hands raised over his head.
#include <algorithm>
#include <cmath>

#include "core/tracking/pose_tracker_impl.h"

namespace lumistage {

namespace {

// How far below the hull's top a crown is looked for: a forearm and a hand held straight up
// reach 0.45 m above the crown of a 2.05 m actor.
constexpr double kDeepestCrownM = 0.5;
// A top closer than this below the hull's is part of the hull's top (a hand's fingers, a second
// hand held at the same height).
constexpr double kShallowestCrownM = 0.08;
// A top is a head's where the hull's section this far below it, within kHeadRadiusM of the top's
// centre, covers kHeadArea of the disc: a head 0.15-0.2 m across covers 0.5-1 of it, a hand or a
// forearm held up a quarter at most.
constexpr double kHeadDepthM = 0.08;
constexpr double kHeadRadiusM = 0.1;
constexpr double kHeadArea = 0.45;
// A top is a raised hand's where that section covers this share of the disc at least (a forearm
// held up, straight or slanted, a fifth to a half; a phantom of the carving, a voxel or two across,
// nothing).
constexpr double kHandArea = 0.1;

}  // namespace

double PoseTracker::Impl::crownBelowRaisedHands() {
  const Eigen::Vector3i lo = occupied_lo, hi = occupied_hi;
  if ((hi.array() < lo.array()).any()) return 0;
  const int nx = hi.x() - lo.x() + 1, ny = hi.y() - lo.y() + 1;
  const size_t gy = size_t(dims.x()), gz = size_t(dims.x()) * dims.y();
  const auto at = [&](int x, int y, int z) {
    return occupied[size_t(z) * gz + size_t(y) * gy + size_t(x)] != 0;
  };
  const int head_depth = int(std::lround(kHeadDepthM / opt.voxel_m));
  const double radius = kHeadRadiusM / opt.voxel_m;
  // The share of the disc about (cx, cy) (voxels) that the hull's section `head_depth` below
  // layer z covers.
  const auto coveredBelow = [&](double cx, double cy, int z) {
    const int zs = std::max(lo.z(), z - head_depth);
    int inside = 0, disc = 0;
    for (int y = int(std::floor(cy - radius)); y <= int(std::ceil(cy + radius)); ++y)
      for (int x = int(std::floor(cx - radius)); x <= int(std::ceil(cx + radius)); ++x) {
        if ((x - cx) * (x - cx) + (y - cy) * (y - cy) > radius * radius) continue;
        ++disc;
        if (x >= lo.x() && x <= hi.x() && y >= lo.y() && y <= hi.y() && at(x, y, zs)) ++inside;
      }
    return double(inside) / disc;
  };
  // Each layer's sections (8-connected), from the top down; a section none of whose voxels has
  // a voxel of the layer above over it (or beside that) is a top of the hull.
  crown_label.assign(size_t(nx) * ny, 0);
  const int deepest = std::max(lo.z(), hi.z() - int(std::lround(kDeepestCrownM / opt.voxel_m)));
  const int shallowest = hi.z() - int(std::lround(kShallowestCrownM / opt.voxel_m));
  int hands = 0;  // the raised hands' tops found above
  for (int z = hi.z(); z >= deepest; --z) {
    std::fill(crown_label.begin(), crown_label.end(), 0);
    int label = 0;
    for (int y0 = lo.y(); y0 <= hi.y(); ++y0)
      for (int x0 = lo.x(); x0 <= hi.x(); ++x0) {
        if (!at(x0, y0, z) || crown_label[size_t(y0 - lo.y()) * nx + (x0 - lo.x())]) continue;
        ++label;
        crown_stack.assign(1, {x0, y0});
        crown_label[size_t(y0 - lo.y()) * nx + (x0 - lo.x())] = label;
        bool covered = false;
        double sx = 0, sy = 0;
        int count = 0;
        while (!crown_stack.empty()) {
          const auto [x, y] = crown_stack.back();
          crown_stack.pop_back();
          sx += x, sy += y, ++count;
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const int u = x + dx, v = y + dy;
              if (u < lo.x() || u > hi.x() || v < lo.y() || v > hi.y()) continue;
              if (z < hi.z() && at(u, v, z + 1)) covered = true;
              int& l = crown_label[size_t(v - lo.y()) * nx + (u - lo.x())];
              if (l || !at(u, v, z)) continue;
              l = label;
              crown_stack.push_back({u, v});
            }
        }
        if (covered) continue;
        // The highest top that is a head's: the hull's own (within kShallowestCrownM of its
        // top) is the crown already; one further below is the crown under raised hands where
        // two hands are raised over it. One hand raised (a wave) is the library's.
        const double covered_share = coveredBelow(sx / count, sy / count, z);
        if (covered_share < kHeadArea) {
          if (covered_share >= kHandArea) ++hands;
          continue;
        }
        return z >= shallowest || hands < 2 ? 0.0 : lower.z() + opt.voxel_m * (z + 1.0);
      }
  }
  return 0;
}

}  // namespace lumistage
