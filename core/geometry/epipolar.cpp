#include "core/geometry/epipolar.h"

#include <Eigen/LU>
#include <algorithm>
#include <limits>

namespace lumistage {

Eigen::Matrix3d fundamentalMatrix(const Camera& a, const Camera& b) {
  // Relative pose a -> b: x_b = R x_a + t.
  const Eigen::Matrix3d R = b.rotation() * a.rotation().transpose();
  const Eigen::Vector3d t = b.translation() - R * a.translation();
  Eigen::Matrix3d tx;
  tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
  const Eigen::Matrix3d E = tx * R;
  return b.intrinsics().matrix().inverse().transpose() * E * a.intrinsics().matrix().inverse();
}

std::vector<Eigen::Vector2d> epipolarCurve(const Camera& a, const Eigen::Vector2d& pixel,
                                           const Camera& b, double near_m, double far_m,
                                           double max_step_px) {
  std::vector<Eigen::Vector2d> out;
  const std::optional<Ray> ray = a.unproject(pixel);
  if (!ray || near_m <= 0 || far_m <= near_m) return out;
  // The ideal (undistorted) pixel in b of the ray's point at inverse depth `inverse`.
  auto ideal = [&](double inverse) -> std::optional<Eigen::Vector2d> {
    const Eigen::Vector3d c = b.toCamera(ray->origin + ray->direction / inverse);
    if (c.z() <= 1e-6) return std::nullopt;
    return b.normalizedToPixel(Eigen::Vector2d(c.x() / c.z(), c.y() / c.z()));
  };
  const double margin_x = 0.25 * b.width(), margin_y = 0.25 * b.height();
  auto keep = [&](const std::optional<Eigen::Vector2d>& p) {
    if (p && p->x() > -margin_x && p->x() < b.width() + margin_x && p->y() > -margin_y &&
        p->y() < b.height() + margin_y) {
      out.push_back(b.distortPixel(*p));
    }
  };
  // Evenly in inverse depth, then halving every step that is still too long in b's image.
  struct Sample {
    double inverse;
    std::optional<Eigen::Vector2d> p;
  };
  const int coarse = 64;
  std::vector<Sample> stack;
  Sample previous{1 / near_m, ideal(1 / near_m)};
  keep(previous.p);
  for (int i = 1; i < coarse; ++i) {
    const double u = double(i) / (coarse - 1);
    const double inverse = (1 - u) / near_m + u / far_m;
    stack.push_back({inverse, ideal(inverse)});
    while (!stack.empty()) {
      const Sample next = stack.back();
      const bool both = previous.p && next.p;
      if (both && (*next.p - *previous.p).norm() > max_step_px &&
          std::abs(next.inverse - previous.inverse) > 1e-9) {
        const double mid = 0.5 * (previous.inverse + next.inverse);
        stack.push_back({mid, ideal(mid)});
        continue;
      }
      stack.pop_back();
      keep(next.p);
      previous = next;
    }
  }
  return out;
}

double distanceToPolyline(const std::vector<Eigen::Vector2d>& polyline,
                          const Eigen::Vector2d& point) {
  double best = std::numeric_limits<double>::infinity();
  if (polyline.size() == 1) return (polyline[0] - point).norm();
  for (size_t i = 0; i + 1 < polyline.size(); ++i) {
    const Eigen::Vector2d d = polyline[i + 1] - polyline[i];
    const double len2 = d.squaredNorm();
    const double s = len2 > 0 ? std::clamp((point - polyline[i]).dot(d) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, (polyline[i] + s * d - point).norm());
  }
  return best;
}

}  // namespace lumistage
