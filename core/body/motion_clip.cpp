#include "core/body/motion_clip.h"

#include <algorithm>
#include <cmath>

namespace lumistage {

namespace {

Eigen::Quaterniond fromRotationVector(const Eigen::Vector3d& v) {
  const double angle = v.norm();
  return angle > 0 ? Eigen::Quaterniond(Eigen::AngleAxisd(angle, v / angle))
                   : Eigen::Quaterniond::Identity();
}

Eigen::Vector3d toRotationVector(const Eigen::Quaterniond& q) {
  const Eigen::AngleAxisd aa(q);
  return aa.angle() * aa.axis();
}

}  // namespace

Pose MotionClip::sample(double time_s) const {
  if (frames.empty()) return {};
  const double position = std::clamp(time_s * fps, 0.0, double(frames.size() - 1));
  const size_t i = std::min(static_cast<size_t>(position), frames.size() - 1);
  const size_t k = std::min(i + 1, frames.size() - 1);
  const double f = position - double(i);
  const Pose& a = frames[i];
  const Pose& b = frames[k];
  Pose out = a;
  out.root_translation_m = (1 - f) * a.root_translation_m + f * b.root_translation_m;
  for (size_t j = 1; j < out.angles_rad.size() && j < b.angles_rad.size(); ++j) {
    out.angles_rad[j] = (1 - f) * a.angles_rad[j] + f * b.angles_rad[j];
  }
  if (!out.angles_rad.empty() && !b.angles_rad.empty()) {
    out.angles_rad[0] = toRotationVector(
        fromRotationVector(a.angles_rad[0]).slerp(f, fromRotationVector(b.angles_rad[0])));
  }
  return out;
}

}  // namespace lumistage
