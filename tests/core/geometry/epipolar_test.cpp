#include "core/geometry/epipolar.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/core/geometry/test_cameras.h"

namespace lumistage {
namespace {

TEST(Epipolar, FundamentalMatrixHoldsForIdealPixels) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 10; ++trial) {
    const Camera a = testing::randomCamera(rng, false, true, "a");
    const Camera b = testing::randomCamera(rng, false, true, "b");
    const Eigen::Matrix3d F = fundamentalMatrix(a, b);
    for (int i = 0; i < 10; ++i) {
      const Eigen::Vector3d x(0.5 * u(rng), 0.5 * u(rng), 1 + 0.5 * u(rng));
      const auto pa = a.project(x);
      const auto pb = b.project(x);
      ASSERT_TRUE(pa && pb);
      // The line F x_a in b, in pixels: the point lies on it.
      const Eigen::Vector3d line = F * pa->homogeneous();
      EXPECT_LT(std::abs(line.dot(pb->homogeneous())) / line.head<2>().norm(), 1e-6);
    }
    // A point off the ray is off the line.
    const auto pa = a.project(Eigen::Vector3d(0, 0, 1));
    const auto pb = b.project(Eigen::Vector3d(0.3, 0, 1));
    const Eigen::Vector3d line = F * pa->homogeneous();
    EXPECT_GT(std::abs(line.dot(pb->homogeneous())) / line.head<2>().norm(), 1.0);
  }
}

TEST(Epipolar, CurvePassesThroughTheOtherImageOfThePoint) {
  // With lens distortion the epipolar line bends; the sampled curve still passes within a pixel
  // of where the other camera sees the point, and far from where it sees another one.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  int checked = 0;
  for (int trial = 0; trial < 10; ++trial) {
    const Camera a = testing::randomCamera(rng, true, false, "a");
    const Camera b = testing::randomCamera(rng, true, false, "b");
    for (int i = 0; i < 5; ++i) {
      const Eigen::Vector3d x(0.5 * u(rng), 0.5 * u(rng), 1 + 0.5 * u(rng));
      const auto pa = a.project(x);
      const auto pb = b.project(x);
      ASSERT_TRUE(pa && pb);
      if (!a.inImage(*pa) || !b.inImage(*pb)) continue;  // the curve is drawn over the image
      ++checked;
      const std::vector<Eigen::Vector2d> curve = epipolarCurve(a, *pa, b, 0.2, 30, 1.0);
      ASSERT_GE(curve.size(), 2u);
      EXPECT_LT(distanceToPolyline(curve, *pb), 1.0);
    }
  }
  EXPECT_GT(checked, 30);
}

TEST(Epipolar, DistanceToPolyline) {
  const std::vector<Eigen::Vector2d> line = {{0, 0}, {10, 0}, {10, 10}};
  EXPECT_DOUBLE_EQ(distanceToPolyline(line, {5, 3}), 3.0);
  EXPECT_DOUBLE_EQ(distanceToPolyline(line, {13, 5}), 3.0);
  EXPECT_DOUBLE_EQ(distanceToPolyline(line, {-4, 3}), 5.0);
  EXPECT_TRUE(std::isinf(distanceToPolyline({}, {0, 0})));
}

}  // namespace
}  // namespace lumistage
