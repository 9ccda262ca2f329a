#pragma once

#include <Eigen/Geometry>
#include <random>
#include <string>

#include "core/geometry/camera.h"

namespace lumistage::testing {

// A random but plausible camera: 640..1920 px wide, a focal length giving 40-80 degrees of
// horizontal view, a principal point near the centre, some skew if asked, OpenCV distortion of a
// real lens if asked, and a pose a few metres from the origin looking roughly at it.
inline Camera randomCamera(std::mt19937& rng, bool distorted, bool skewed = false,
                           const std::string& name = "cam") {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int width = 640 + static_cast<int>((u(rng) + 1) * 640);
  const int height = width * 3 / 4;
  const double fov = (60 + 20 * u(rng)) * 3.14159265358979 / 180;
  Intrinsics k;
  k.fx = 0.5 * width / std::tan(fov / 2);
  k.fy = k.fx * (1 + 0.01 * u(rng));
  k.cx = 0.5 * width + 20 * u(rng);
  k.cy = 0.5 * height + 20 * u(rng);
  k.skew = skewed ? 2 * u(rng) : 0;
  Distortion d;
  // Coefficients of real lenses of that field of view: monotonic over the whole image.
  if (distorted) {
    d = {-0.07 + 0.05 * u(rng), 0.01 + 0.02 * u(rng), 0.001 * u(rng), 0.001 * u(rng),
         0.002 * u(rng)};
  }
  const Eigen::Vector3d centre(3 * u(rng), 3 * u(rng), 1 + u(rng));
  const Eigen::Vector3d target(0.3 * u(rng), 0.3 * u(rng), 1 + 0.2 * u(rng));
  const Eigen::Vector3d z = (target - centre).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d(0.1 * u(rng), 0.1 * u(rng), 1)).normalized();
  Eigen::Matrix3d R;
  R.row(0) = x;
  R.row(1) = z.cross(x);
  R.row(2) = z;
  return Camera(name, width, height, k, d, R, -R * centre);
}

}  // namespace lumistage::testing
