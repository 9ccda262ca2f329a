// The tracker's view of each silhouette beyond its hull (PoseTracker::Impl, pose_tracker_impl.h):
// the rays through its edges that the fit's rim term holds the body to, and the camera whose
// silhouette disagrees with every other's, left out of a frame.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/tracking/pose_tracker_impl.h"

namespace lumistage {

using namespace tracker_detail;

void PoseTracker::Impl::sampleRim(const LowResSilhouette& s, int count) {
  const int w = s.width, h = s.height;
  // Edge cells: inside, with a 4-neighbour outside (the image's border is no edge: the body goes
  // on beyond it); `n` the way out. Asked within the silhouette's box, on the image.
  const auto edge = [&](int x, int y, Eigen::Vector2d& n) {
    if (!s.at(x, y)) return false;
    n.setZero();
    if (x > 0 && !s.at(x - 1, y)) n.x() -= 1;
    if (x + 1 < w && !s.at(x + 1, y)) n.x() += 1;
    if (y > 0 && !s.at(x, y - 1)) n.y() -= 1;
    if (y + 1 < h && !s.at(x, y + 1)) n.y() += 1;
    return n.squaredNorm() > 0;
  };
  const Eigen::Array4i& box = dt_box[s.camera];
  int edges = 0;
  Eigen::Vector2d n;
  for (int y = box[1]; y <= box[3]; ++y)
    for (int x = box[0]; x <= box[2]; ++x) edges += edge(x, y, n);
  if (edges == 0 || count <= 0) return;
  const Camera& cam = rig.camera(s.camera);
  const double step = s.step;
  int k = 0, taken = 0;
  for (int y = box[1]; y <= box[3]; ++y) {
    for (int x = box[0]; x <= box[2]; ++x) {
      if (!edge(x, y, n)) continue;
      // Evenly: edge k is taken when it passes the next of `count` marks.
      if (int64_t(k++) * count / edges < taken) continue;
      ++taken;
      const Eigen::Vector2d pixel =
          Eigen::Vector2d((x + 0.5) * step - 0.5, (y + 0.5) * step - 0.5) +
          0.5 * step * n.normalized();
      if (const std::optional<Ray> ray = cam.unproject(pixel))
        rim.push_back({ray->origin, ray->direction, s.camera, y * w + x});
    }
  }
}

void PoseTracker::Impl::dropRimRaysOffHull() {
  const Eigen::Vector3i lo = occupied_lo, hi = occupied_hi;
  if (rim.empty() || (hi.array() < lo.array()).any()) return;
  const size_t gy = size_t(dims.x()), gz = size_t(dims.x()) * dims.y();
  // Whether voxel v, or one of its six face neighbours, is occupied.
  const auto nearHull = [&](const Eigen::Vector3i& v) {
    const auto at = [&](int x, int y, int z) {
      return x >= lo.x() && y >= lo.y() && z >= lo.z() && x <= hi.x() && y <= hi.y() &&
             z <= hi.z() && occupied[size_t(z) * gz + size_t(y) * gy + size_t(x)];
    };
    const int x = v.x(), y = v.y(), z = v.z();
    return at(x, y, z) || at(x - 1, y, z) || at(x + 1, y, z) || at(x, y - 1, z) ||
           at(x, y + 1, z) || at(x, y, z - 1) || at(x, y, z + 1);
  };
  // The occupied box grown by a voxel, metres; each ray's stretch inside it (slabs) walked a
  // voxel at a time.
  const Eigen::Vector3d box_lo = lower + opt.voxel_m * (lo.cast<double>().array() - 1).matrix();
  const Eigen::Vector3d box_hi = lower + opt.voxel_m * (hi.cast<double>().array() + 2).matrix();
  const auto meetsHull = [&](const RimRay& r) {
    double t0 = 0, t1 = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (std::abs(r.direction[a]) < 1e-12) {
        if (r.origin[a] < box_lo[a] || r.origin[a] > box_hi[a]) return false;
        continue;
      }
      double ta = (box_lo[a] - r.origin[a]) / r.direction[a];
      double tb = (box_hi[a] - r.origin[a]) / r.direction[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    for (double t = t0; t <= t1; t += opt.voxel_m)
      if (nearHull(
              ((r.origin + t * r.direction - lower) / opt.voxel_m).array().floor().cast<int>()))
        return true;
    return false;
  };
  rim_on_hull.resize(rim.size());
  bool any_off = false;
  for (size_t i = 0; i < rim.size(); ++i) {
    rim_on_hull[i] = meetsHull(rim[i]);
    any_off |= !rim_on_hull[i];
  }
  if (!any_off) return;
  // A ray that misses the hull is kept where its edge belongs to a part of the silhouette (its
  // 8-connected cells) through whose edge another ray meets it: the body's own edge, where the
  // hull lies a little inside it or lost a limb another camera's key missed. Each such part is
  // walked from a missing ray's cell until a meeting ray's is reached (its cells then marked
  // kept) or the part ends (marked dropped).
  constexpr uint8_t kKept = 1, kDropped = 2, kWalked = 3;
  // Each camera's rays lie together in the rim (sampleRim): a run at a time.
  for (size_t begin = 0, end = 0; begin < rim.size(); begin = end) {
    const int c = rim[begin].camera;
    bool off = false;
    for (end = begin; end < rim.size() && rim[end].camera == c; ++end) off |= !rim_on_hull[end];
    const LowResSilhouette* s = frame_silhouettes[size_t(c)];
    if (!off || !s) continue;
    const int w = s->width, h = s->height;
    if (rim_part.size() < size_t(w) * h) rim_part.assign(size_t(w) * h, 0);
    rim_touched.clear();
    const auto mark = [&](int cell, uint8_t m) {
      if (!rim_part[size_t(cell)]) rim_touched.push_back(cell);
      rim_part[size_t(cell)] = m;
    };
    for (size_t i = begin; i < end; ++i)
      if (rim_on_hull[i]) mark(rim[i].cell, kKept);
    for (size_t i = begin; i < end; ++i) {
      if (rim_on_hull[i]) continue;
      uint8_t fate = rim_part[size_t(rim[i].cell)];
      if (fate != kKept && fate != kDropped) {
        // Breadth first, so that the body's nearest meeting ray ends the walk soon.
        const size_t walk_begin = rim_touched.size();
        rim_flood.assign(1, rim[i].cell);
        mark(rim[i].cell, kWalked);
        fate = kDropped;
        for (size_t q = 0; q < rim_flood.size() && fate == kDropped; ++q) {
          const int x = rim_flood[q] % w, y = rim_flood[q] / w;
          for (int ny = std::max(0, y - 1); ny <= std::min(h - 1, y + 1); ++ny)
            for (int nx = std::max(0, x - 1); nx <= std::min(w - 1, x + 1); ++nx) {
              const int n = ny * w + nx;
              const uint8_t m = rim_part[size_t(n)];
              if (m == kKept) fate = kKept;
              if (m || !s->at(nx, ny)) continue;
              mark(n, kWalked);
              rim_flood.push_back(n);
            }
        }
        for (size_t k = walk_begin; k < rim_touched.size(); ++k)
          rim_part[size_t(rim_touched[k])] = fate;
      }
      rim_on_hull[i] = fate == kKept;
    }
    for (int cell : rim_touched) rim_part[size_t(cell)] = 0;
  }
  size_t kept = 0;
  for (size_t i = 0; i < rim.size(); ++i)
    if (rim_on_hull[i]) rim[kept++] = rim[i];
  rim.resize(kept);
  candidates_valid = false;
}

int PoseTracker::Impl::leaveOutDisagreeingCamera() {
  // A sample this many cells outside a silhouette is missed by it; a camera that misses more than
  // kMissed of them while none of the others misses more than kHeld is left out.
  constexpr float kOutsideCells = 2.0f;
  constexpr double kMissed = 0.3, kHeld = 0.12;
  int given = 0;
  for (int c = 0; c < cameras; ++c) given += present[c];
  if (given < 4) return -1;
  double worst = 0, second = 0;
  int worst_c = -1;
  const int step = opt.silhouette_step;
  for (int c = 0; c < cameras; ++c) {
    if (!present[c]) continue;
    const Camera& cam = rig.camera(c);
    int seen = 0, missed = 0;
    for (const Sample& s : samples) {
      const auto pix = cam.project(global[s.joint] * s.local);
      if (!pix) continue;
      const int x = int((*pix)(0) / step), y = int((*pix)(1) / step);
      if (x < 0 || y < 0 || x >= cell_w[c] || y >= cell_h[c]) continue;
      ++seen;
      missed += dt[c][size_t(y) * cell_w[c] + x] > kOutsideCells;
    }
    const double share = seen > 0 ? double(missed) / seen : 0.0;
    if (share > worst) {
      second = worst, worst = share, worst_c = c;
    } else {
      second = std::max(second, share);
    }
  }
  if (worst_c < 0 || worst <= kMissed || second > kHeld) return -1;
  present[worst_c] = 0;
  return worst_c;
}

}  // namespace lumistage
