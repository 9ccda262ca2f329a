// The hull's length from the soles to the crown (PoseTracker::Impl::crownToSole,
// pose_tracker_impl.h): a body's height whatever its posture.
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>

#include "core/tracking/pose_tracker_impl.h"

namespace lumistage {

namespace {

// A step of the shortest path: to a voxel up to two away in each axis (no multiple of a shorter
// step), its length in voxels. Steps of one voxel alone (26 neighbours) measure a path 20 degrees
// off an axis 8 % long; these, within 2 %.
struct Step {
  Eigen::Vector3i d;
  float length;
};

const std::vector<Step>& steps() {
  static const std::vector<Step> table = [] {
    std::vector<Step> t;
    for (int z = -2; z <= 2; ++z)
      for (int y = -2; y <= 2; ++y)
        for (int x = -2; x <= 2; ++x) {
          if (std::gcd(std::gcd(std::abs(x), std::abs(y)), std::abs(z)) != 1) continue;
          t.push_back({Eigen::Vector3i(x, y, z), float(std::sqrt(double(x * x + y * y + z * z)))});
        }
    return t;
  }();
  return table;
}

}  // namespace

double PoseTracker::Impl::crownToSole(const Pose& p) {
  const Eigen::Vector3i lo = occupied_lo, hi = occupied_hi;
  if ((hi.array() < lo.array()).any()) return 0;
  // The occupied box copied with a border of two empty voxels, so that no step needs a bounds
  // check: its voxels' indices, and each step's (and its halfway voxels') index offset.
  const Eigen::Vector3i n = hi - lo + Eigen::Vector3i::Constant(5);
  const int sy = n.x(), sz = n.x() * n.y();
  const auto localIndex = [&](const Eigen::Vector3i& v) {
    const Eigen::Vector3i l = v - lo + Eigen::Vector3i::Constant(2);
    return l.z() * sz + l.y() * sy + l.x();
  };
  const size_t gy = size_t(dims.x()), gz = size_t(dims.x()) * dims.y();
  geodesic_inside.assign(size_t(sz) * n.z(), 0);
  for (int z = lo.z(); z <= hi.z(); ++z)
    for (int y = lo.y(); y <= hi.y(); ++y) {
      const uint8_t* row = &occupied[size_t(z) * gz + size_t(y) * gy + size_t(lo.x())];
      std::copy(row, row + (hi.x() - lo.x() + 1),
                &geodesic_inside[size_t(localIndex(Eigen::Vector3i(lo.x(), y, z)))]);
    }
  struct Offset {
    int step, half_lo, half_hi;
    float length;
  };
  Offset offsets[128];
  int offset_count = 0;
  for (const Step& s : steps()) {
    const auto delta = [&](const Eigen::Vector3i& d) { return d.z() * sz + d.y() * sy + d.x(); };
    offsets[offset_count++] = {delta(s.d), delta(s.d.unaryExpr([](int c) { return c / 2; })),
                               delta(s.d.unaryExpr([](int c) { return c - c / 2; })), s.length};
  }
  constexpr float kFar = std::numeric_limits<float>::infinity();
  geodesic.assign(geodesic_inside.size(), kFar);
  geodesic_heap.clear();
  const auto later = std::greater<std::pair<float, int>>();
  // From every sole: the voxels of the hull's two lowest layers.
  for (int z = lo.z(); z <= std::min(hi.z(), lo.z() + 1); ++z)
    for (int y = lo.y(); y <= hi.y(); ++y)
      for (int x = lo.x(); x <= hi.x(); ++x) {
        const int i = localIndex(Eigen::Vector3i(x, y, z));
        if (!geodesic_inside[size_t(i)]) continue;
        geodesic[size_t(i)] = 0;
        geodesic_heap.emplace_back(0.0f, i);
      }
  std::make_heap(geodesic_heap.begin(), geodesic_heap.end(), later);
  while (!geodesic_heap.empty()) {
    std::pop_heap(geodesic_heap.begin(), geodesic_heap.end(), later);
    const auto [d, i] = geodesic_heap.back();
    geodesic_heap.pop_back();
    if (d > geodesic[size_t(i)]) continue;
    for (int k = 0; k < offset_count; ++k) {
      const Offset& o = offsets[k];
      const int j = i + o.step;
      // A long step crosses the voxels halfway: both inside, so that it jumps no gap.
      if (!geodesic_inside[size_t(j)] || !geodesic_inside[size_t(i + o.half_lo)] ||
          !geodesic_inside[size_t(i + o.half_hi)])
        continue;
      const float dj = d + o.length;
      if (dj < geodesic[size_t(j)]) {
        geodesic[size_t(j)] = dj;
        geodesic_heap.emplace_back(dj, j);
        std::push_heap(geodesic_heap.begin(), geodesic_heap.end(), later);
      }
    }
  }
  // The crown: the voxel furthest from the soles within the head's reach of its joint.
  skeleton.forwardKinematics(p, global);
  const double scale = skeleton.restPositions()[kHead].z() / generic_head_z;
  const double reach = (generic_top_z - generic_head_z) * scale + 0.04;
  const Eigen::Vector3d head = (global[kHead].translation() - lower) / opt.voxel_m;
  const double r = reach / opt.voxel_m;
  const Eigen::Vector3i a = (head.array() - r).floor().cast<int>().max(lo.array()).matrix(),
                        b = (head.array() + r).ceil().cast<int>().min(hi.array()).matrix();
  float crown = -1;
  for (int z = a.z(); z <= b.z(); ++z)
    for (int y = a.y(); y <= b.y(); ++y)
      for (int x = a.x(); x <= b.x(); ++x) {
        const Eigen::Vector3i v(x, y, z);
        if ((Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5) - head).norm() > r) continue;
        const float d = geodesic[size_t(localIndex(v))];
        if (d < kFar) crown = std::max(crown, d);
      }
  // From the soles' floor to the crown's top: half a voxel beyond each end's centre.
  return crown < 0 ? 0.0 : (double(crown) + 1.0) * opt.voxel_m;
}

}  // namespace lumistage
