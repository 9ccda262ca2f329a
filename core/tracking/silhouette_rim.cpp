// The tracker's view of each silhouette beyond its hull (PoseTracker::Impl, pose_tracker_impl.h):
// the rays through its edges that the fit's rim term holds the body to, and the camera whose
// silhouette disagrees with every other's, left out of a frame.
#include <algorithm>
#include <cstdint>

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
        rim.push_back({ray->origin, ray->direction, s.camera});
    }
  }
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
