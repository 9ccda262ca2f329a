#include "core/render/camera_path.h"

#include <algorithm>
#include <cmath>

namespace lumistage {

void CameraPath::setKey(double time_s, const ViewPose& pose) {
  for (CameraKey& key : keys_) {
    if (std::abs(key.time_s - time_s) < 1e-3) {
      key.pose = pose;
      return;
    }
  }
  const auto at = std::lower_bound(keys_.begin(), keys_.end(), time_s,
                                   [](const CameraKey& k, double t) { return k.time_s < t; });
  keys_.insert(at, CameraKey{time_s, pose});
}

bool CameraPath::removeKey(double time_s, double tolerance_s) {
  auto best = keys_.end();
  double best_dt = tolerance_s;
  for (auto it = keys_.begin(); it != keys_.end(); ++it) {
    const double dt = std::abs(it->time_s - time_s);
    if (dt <= best_dt) {
      best_dt = dt;
      best = it;
    }
  }
  if (best == keys_.end()) return false;
  keys_.erase(best);
  return true;
}

ViewPose CameraPath::at(double time_s) const {
  if (keys_.empty()) return {};
  if (time_s <= keys_.front().time_s) return keys_.front().pose;
  if (time_s >= keys_.back().time_s) return keys_.back().pose;
  size_t i = 0;
  while (keys_[i + 1].time_s < time_s) ++i;
  const CameraKey &a = keys_[i], &b = keys_[i + 1];
  const double span = b.time_s - a.time_s;
  const double u = span > 0 ? (time_s - a.time_s) / span : 0;
  // Catmull-Rom through the neighbours (the end keys repeated at the ends).
  const Eigen::Vector3d& p1 = a.pose.eye;
  const Eigen::Vector3d& p2 = b.pose.eye;
  const Eigen::Vector3d& p0 = i > 0 ? keys_[i - 1].pose.eye : p1;
  const Eigen::Vector3d& p3 = i + 2 < keys_.size() ? keys_[i + 2].pose.eye : p2;
  const double u2 = u * u, u3 = u2 * u;
  ViewPose out;
  out.eye = 0.5 * ((2 * p1) + (-p0 + p2) * u + (2 * p0 - 5 * p1 + 4 * p2 - p3) * u2 +
                   (-p0 + 3 * p1 - 3 * p2 + p3) * u3);
  out.orientation = a.pose.orientation.normalized().slerp(u, b.pose.orientation.normalized());
  out.fov_y_rad = a.pose.fov_y_rad + u * (b.pose.fov_y_rad - a.pose.fov_y_rad);
  return out;
}

}  // namespace lumistage
