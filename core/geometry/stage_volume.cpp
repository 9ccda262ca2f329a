#include "core/geometry/stage_volume.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace lumistage {

int minViewsForStage(int cameras) {
  return cameras <= 4 ? cameras : (3 * cameras + 3) / 4;
}

std::optional<StageBox> coveredStage(const Rig& rig) {
  const int cameras = rig.cameraCount();
  if (cameras == 0) return std::nullopt;
  // The search reaches a little past the cameras themselves (a stage lies among its cameras), on
  // a grid of at most 161 x 161 columns: 5 cm steps up to a ring of 3.3 m, coarser beyond (a rig
  // whose units are not metres must not take minutes here).
  double reach = 2.0;
  for (const Camera& c : rig.cameras()) reach = std::max(reach, 1.2 * c.centre().head<2>().norm());
  constexpr int kHalfColumns = 80;
  const double step = std::max(0.05, reach / kHalfColumns);
  const int need = minViewsForStage(cameras);
  Eigen::Vector2d lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
  const auto inImage = [](const Camera& c, const Eigen::Vector3d& p) {
    if ((c.rotation() * p + c.translation()).z() <= 0) return false;
    const std::optional<Eigen::Vector2d> px = c.project(p);
    return px && px->x() >= -0.5 && px->y() >= -0.5 && px->x() <= c.width() - 0.5 &&
           px->y() <= c.height() - 0.5;
  };
  const int n = int(std::ceil(reach / step));
  for (int iy = -n; iy <= n; ++iy) {
    for (int ix = -n; ix <= n; ++ix) {
      const Eigen::Vector2d xy(ix * step, iy * step);
      int seen = 0;
      for (const Camera& c : rig.cameras()) {
        seen += inImage(c, {xy.x(), xy.y(), 0.0}) && inImage(c, {xy.x(), xy.y(), kCoveredTop_m});
      }
      if (seen < need) continue;
      lo = lo.cwiseMin(xy);
      hi = hi.cwiseMax(xy);
    }
  }
  if (lo.x() > hi.x()) return std::nullopt;
  // Never less than the default box's floor (what the tracker searched before the box came from
  // the rig: a rig whose cameras barely agree does not shrink it to a spot), never more than
  // kMaxCoveredSide_m a side (its tables, and an empty stage's frame, grow with the floor).
  const StageBox least;
  StageBox box;
  constexpr double kRound = 0.1;
  for (int k = 0; k < 2; ++k) {
    double a = std::min(least.lower[k], kRound * std::floor((lo[k] - 0.5 * step) / kRound + 1e-9));
    double b = std::max(least.upper[k], kRound * std::ceil((hi[k] + 0.5 * step) / kRound - 1e-9));
    if (b - a > kMaxCoveredSide_m) {
      const double centre = kRound * std::round(0.5 * (a + b) / kRound);
      a = centre - 0.5 * kMaxCoveredSide_m, b = centre + 0.5 * kMaxCoveredSide_m;
    }
    box.lower[k] = a, box.upper[k] = b;
  }
  box.lower.z() = 0;
  box.upper.z() = kCoveredTop_m;
  return box;
}

StageChoice chooseStage(const Rig& rig) {
  StageChoice choice;
  if (rig.stage()) {
    choice.box = *rig.stage();
    choice.how = describeStage(choice.box) + ", from the rig file";
  } else if (const std::optional<StageBox> covered = coveredStage(rig)) {
    choice.box = *covered;
    choice.how = fmt::format("{}, the floor that {} of the {} cameras see whole up to {} m",
                             describeStage(choice.box), minViewsForStage(rig.cameraCount()),
                             rig.cameraCount(), kCoveredTop_m);
  } else {
    choice.guessed = true;
    choice.how = fmt::format(
        "{}, a guess: no floor is seen whole by {} of the {} cameras; give the rig file a "
        "`stage` (docs/rig-file.md)",
        describeStage(choice.box), minViewsForStage(rig.cameraCount()), rig.cameraCount());
  }
  return choice;
}

std::string describeStage(const StageBox& box) {
  const Eigen::Vector3d size = box.size(), centre = 0.5 * (box.lower + box.upper);
  return fmt::format("{:.1f} x {:.1f} m floor, {:.1f} m high, centred on ({:.1f}, {:.1f})",
                     size.x(), size.y(), box.upper.z(), centre.x(), centre.y());
}

}  // namespace lumistage
