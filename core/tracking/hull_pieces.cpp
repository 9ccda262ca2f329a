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
  // The occupied box's voxels labelled by their 26-connected piece (1, 2, ...).
  piece_label.assign(size_t(n.x()) * n.y() * n.z(), 0);
  pieces.clear();
  for (int z = lo.z(); z <= hi.z(); ++z)
    for (int y = lo.y(); y <= hi.y(); ++y)
      for (int x = lo.x(); x <= hi.x(); ++x) {
        const Eigen::Vector3i seed(x, y, z);
        if (!occupied[grid(seed)] || piece_label[local(seed)]) continue;
        const int label = int(pieces.size()) + 1;
        Piece piece{0, Eigen::Vector3d::Zero(), seed, seed};
        piece_label[local(seed)] = label;
        piece_stack.assign(1, seed);
        while (!piece_stack.empty()) {
          const Eigen::Vector3i v = piece_stack.back();
          piece_stack.pop_back();
          ++piece.voxels;
          piece.sum += v.cast<double>();
          piece.lo = piece.lo.cwiseMin(v);
          piece.hi = piece.hi.cwiseMax(v);
          for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx) {
                const Eigen::Vector3i w = v + Eigen::Vector3i(dx, dy, dz);
                if ((w.array() < lo.array()).any() || (w.array() > hi.array()).any()) continue;
                if (!occupied[grid(w)] || piece_label[local(w)]) continue;
                piece_label[local(w)] = label;
                piece_stack.push_back(w);
              }
        }
        pieces.push_back(piece);
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
