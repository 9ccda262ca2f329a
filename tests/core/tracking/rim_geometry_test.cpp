// The rim term's geometry: the distance between a viewing ray and a capsule's axis, with the
// closest points whose difference gives the fit its slope.
#include <gtest/gtest.h>

#include "core/tracking/pose_tracker_impl.h"

namespace lumistage {
namespace {

using tracker_detail::raySegmentDistance;

TEST(RimGeometry, ARayPassingASegmentMeetsItAtTheirCommonPerpendicular) {
  // The ray along x at height 1 and y 0.5; the segment along y at height 0.
  Eigen::Vector3d on_ray, on_segment;
  const double d =
      raySegmentDistance({-2, 0.5, 1}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, on_ray, on_segment);
  EXPECT_NEAR(d, 1.0, 1e-12);
  EXPECT_TRUE(on_ray.isApprox(Eigen::Vector3d(0, 0.5, 1)));
  EXPECT_TRUE(on_segment.isApprox(Eigen::Vector3d(0, 0.5, 0)));
}

TEST(RimGeometry, TheSegmentsEndsAndTheRaysOriginBoundTheClosestPoints) {
  Eigen::Vector3d on_ray, on_segment;
  // The perpendicular would meet the segment's line beyond its end b = (0, 1, 0).
  double d = raySegmentDistance({-2, 3, 1}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, on_ray, on_segment);
  EXPECT_TRUE(on_segment.isApprox(Eigen::Vector3d(0, 1, 0)));
  EXPECT_TRUE(on_ray.isApprox(Eigen::Vector3d(0, 3, 1)));
  EXPECT_NEAR(d, std::sqrt(5.0), 1e-12);
  // A segment behind the ray's origin: the origin is the ray's closest point.
  d = raySegmentDistance({2, 0, 1}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, on_ray, on_segment);
  EXPECT_TRUE(on_ray.isApprox(Eigen::Vector3d(2, 0, 1)));
  EXPECT_TRUE(on_segment.isApprox(Eigen::Vector3d(0, 0, 0)));
  EXPECT_NEAR(d, std::sqrt(5.0), 1e-12);
  // Parallel: any common perpendicular; the distance is the lines'.
  d = raySegmentDistance({-2, 0, 1}, {1, 0, 0}, {0, 0, 0}, {1, 0, 0}, on_ray, on_segment);
  EXPECT_NEAR(d, 1.0, 1e-12);
  EXPECT_NEAR((on_ray - on_segment).norm(), 1.0, 1e-12);
}

}  // namespace
}  // namespace lumistage
