// The hull's pieces (PoseTracker::Impl::dropStrayPieces, pose_tracker_impl.h): what the carving
// keeps far from the actor left out of the hull the initialisation searches.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "core/tracking/pose_tracker_impl.h"

namespace lumistage {

namespace {

// A piece of the hull whose box comes within this of the largest piece's is the actor's (a hand
// or a foot the key cut off at the wrist or the ankle); one further away is not.
constexpr double kNearActorM = 0.15;

}  // namespace

double PoseTracker::Impl::dropStrayPieces(Eigen::Vector3d& centroid, double& top_z,
                                          double& bottom_z) {
  const Eigen::Vector3i lo = occupied_lo, hi = occupied_hi;
  if ((hi.array() < lo.array()).any()) return 0;
  const Eigen::Vector3i n = hi - lo + Eigen::Vector3i::Ones();
  const size_t gy = size_t(dims.x()), gz = size_t(dims.x()) * dims.y();
  const auto grid = [&](const Eigen::Vector3i& v) {
    return size_t(v.z()) * gz + size_t(v.y()) * gy + size_t(v.x());
  };
  const auto local = [&](const Eigen::Vector3i& v) {
    const Eigen::Vector3i l = v - lo;
    return (size_t(l.z()) * n.y() + l.y()) * n.x() + l.x();
  };
  // The occupied box's voxels labelled by their 26-connected piece (1, 2, ...), a flood from each
  // unlabelled voxel over index steps (a junk hull of a grey stage keyed green fills the stage's
  // box: millions of voxels, each step's neighbours tested by their indices alone).
  const size_t nx = size_t(n.x()), nxy = nx * size_t(n.y());
  struct Step {
    ptrdiff_t local, grid;
    int dx, dy, dz;
  };
  Step steps[26];
  int k = 0;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        if (dx || dy || dz)
          steps[k++] = {ptrdiff_t(dz) * ptrdiff_t(nxy) + ptrdiff_t(dy) * ptrdiff_t(nx) + dx,
                        ptrdiff_t(dz) * ptrdiff_t(gz) + ptrdiff_t(dy) * ptrdiff_t(gy) + dx, dx, dy,
                        dz};
  piece_label.assign(nxy * size_t(n.z()), 0);
  pieces.clear();
  size_t seed = 0;
  for (int z = lo.z(); z <= hi.z(); ++z)
    for (int y = lo.y(); y <= hi.y(); ++y) {
      size_t g = grid(Eigen::Vector3i(lo.x(), y, z));
      for (int x = lo.x(); x <= hi.x(); ++x, ++seed, ++g) {
        if (!occupied[g] || piece_label[seed]) continue;
        const int label = int(pieces.size()) + 1;
        const Eigen::Vector3i first(x, y, z);
        Piece piece{0, Eigen::Vector3d::Zero(), first, first};
        piece_label[seed] = label;
        piece_stack.assign(1, seed);
        while (!piece_stack.empty()) {
          const size_t l = piece_stack.back();
          piece_stack.pop_back();
          const int lx = int(l % nx), ly = int(l / nx % size_t(n.y())), lz = int(l / nxy);
          const Eigen::Vector3i v = lo + Eigen::Vector3i(lx, ly, lz);
          ++piece.voxels;
          piece.sum += v.cast<double>();
          piece.lo = piece.lo.cwiseMin(v);
          piece.hi = piece.hi.cwiseMax(v);
          const size_t gv = grid(v);
          const bool inside =
              lx > 0 && ly > 0 && lz > 0 && lx < n.x() - 1 && ly < n.y() - 1 && lz < n.z() - 1;
          for (const Step& s : steps) {
            if (!inside && (lx + s.dx < 0 || ly + s.dy < 0 || lz + s.dz < 0 || lx + s.dx >= n.x() ||
                            ly + s.dy >= n.y() || lz + s.dz >= n.z()))
              continue;
            const size_t w = size_t(ptrdiff_t(l) + s.local);
            if (piece_label[w] || !occupied[size_t(ptrdiff_t(gv) + s.grid)]) continue;
            piece_label[w] = label;
            piece_stack.push_back(w);
          }
        }
        pieces.push_back(piece);
      }
    }
  if (pieces.size() < 2) return 0;
  const auto largest =
      std::max_element(pieces.begin(), pieces.end(),
                       [](const Piece& a, const Piece& b) { return a.voxels < b.voxels; });
  const int near = int(std::ceil(kNearActorM / opt.voxel_m));
  const Eigen::Array3i near_lo = largest->lo.array() - near, near_hi = largest->hi.array() + near;
  for (Piece& p : pieces)
    p.kept = (p.hi.array() >= near_lo).all() && (p.lo.array() <= near_hi).all();
  // The kept pieces' box, centroid, top and bottom; the others' voxels cleared.
  int count = 0, dropped = 0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Vector3i kept_lo = hi, kept_hi = lo;
  for (const Piece& p : pieces) {
    if (!p.kept) {
      dropped += p.voxels;
      continue;
    }
    count += p.voxels;
    sum += p.sum;
    kept_lo = kept_lo.cwiseMin(p.lo);
    kept_hi = kept_hi.cwiseMax(p.hi);
  }
  if (dropped == 0) return 0;
  for (int z = lo.z(); z <= hi.z(); ++z)
    for (int y = lo.y(); y <= hi.y(); ++y)
      for (int x = lo.x(); x <= hi.x(); ++x) {
        const Eigen::Vector3i v(x, y, z);
        const int label = piece_label[local(v)];
        if (label && !pieces[size_t(label - 1)].kept) occupied[grid(v)] = 0;
      }
  spdlog::debug("tracker: {} voxels of the hull apart from the actor's left out", dropped);
  occupied_lo = kept_lo, occupied_hi = kept_hi;
  sampleSurface(Eigen::Vector3i::Zero(), dims - Eigen::Vector3i::Ones());
  centroid = lower + opt.voxel_m * (sum / count + Eigen::Vector3d::Constant(0.5));
  top_z = lower.z() + opt.voxel_m * (kept_hi.z() + 1.0);
  bottom_z = lower.z() + opt.voxel_m * kept_lo.z();
  return count * std::pow(opt.voxel_m, 3);
}

}  // namespace lumistage
