// Low-resolution depth maps: depths of a known sphere, and what they hide.
#include "core/refine/depth_map.h"

#include <gtest/gtest.h>

#include "tests/core/refine/refine_test_scene.h"

namespace lumistage {
namespace {

TEST(DepthMap, DepthsOfASphereAndItsHiddenSide) {
  const Rig rig = testing::smallRing(640, 480);
  const Eigen::Vector3d centre(0, 0, 1.0);
  const double radius = 0.3;
  const TriangleMesh sphere = testing::icosphere(centre, radius, 4);
  const Camera& camera = rig.camera(0);
  DepthMap map;
  map.render(camera, sphere.positions, sphere.triangles, 8);
  EXPECT_EQ(map.width(), 80);
  EXPECT_EQ(map.height(), 60);
  const Eigen::Vector3d c = camera.centre();
  const Eigen::Vector3d toward = (c - centre).normalized();
  // The sphere's nearest point: depth along the optical axis within a few mm (flat facets).
  const Eigen::Vector3d front = centre + radius * toward, back = centre - radius * toward;
  const Eigen::Vector2d pf = *camera.project(front);
  const float depth_front = float(camera.toCamera(front).z());
  EXPECT_NEAR(map.depthAt(float(pf.x()), float(pf.y())), depth_front, 0.01);
  EXPECT_TRUE(map.visible(float(pf.x()), float(pf.y()), depth_front, 0.02f));
  const Eigen::Vector2d pb = *camera.project(back);
  EXPECT_FALSE(map.visible(float(pb.x()), float(pb.y()), float(camera.toCamera(back).z()), 0.02f));
  // Off the sphere: nothing.
  EXPECT_EQ(map.depthAt(2, 2), DepthMap::kFar);
  EXPECT_EQ(map.depthAt(-10, 5), DepthMap::kFar);
  // Every sphere vertex facing the camera is visible, every one facing away hidden (away from
  // the rim, where the low resolution decides).
  Eigen::Matrix2Xf pixels;
  Eigen::VectorXf depths;
  camera.project(sphere.positions, pixels, depths);
  int wrong = 0, counted = 0;
  for (int v = 0; v < sphere.vertexCount(); ++v) {
    const Eigen::Vector3f p = sphere.positions.col(v);
    const float facing = sphere.normals.col(v).dot((c.cast<float>() - p).normalized());
    if (std::abs(facing) < 0.5f) continue;
    ++counted;
    wrong += map.visible(pixels(0, v), pixels(1, v), depths(v), 0.02f) != (facing > 0);
  }
  EXPECT_GT(counted, 800);
  EXPECT_EQ(wrong, 0);
}

// The nearest surface of a closed mesh is a front face: back faces are not drawn, so the same
// sphere wound the other way round shows its far side (its inside seen from within).
TEST(DepthMap, BackFacesAreNotDrawn) {
  const Rig rig = testing::smallRing(640, 480);
  const Eigen::Vector3d centre(0, 0, 1.0);
  const double radius = 0.3;
  TriangleMesh sphere = testing::icosphere(centre, radius, 3);
  const Camera& camera = rig.camera(0);
  const Eigen::Vector2d pixel = *camera.project(centre);
  const double to_centre = camera.toCamera(centre).z();
  DepthMap map;
  map.render(camera, sphere.positions, sphere.triangles, 4);
  EXPECT_NEAR(map.depthAt(float(pixel.x()), float(pixel.y())), to_centre - radius, 0.01);
  for (Eigen::Vector3i& t : sphere.triangles) std::swap(t[1], t[2]);
  map.render(camera, sphere.positions, sphere.triangles, 4);
  EXPECT_NEAR(map.depthAt(float(pixel.x()), float(pixel.y())), to_centre + radius, 0.01);
}

// A triangle that names a vertex the mesh does not have (a malformed mesh) is left out, not read
// beyond the vertices.
TEST(DepthMap, TrianglesOfVerticesNotGivenAreLeftOut) {
  const Rig rig = testing::smallRing(640, 480);
  TriangleMesh sphere = testing::icosphere({0, 0, 1.0}, 0.3, 2);
  const Camera& camera = rig.camera(0);
  DepthMap whole, with_bad;
  whole.render(camera, sphere.positions, sphere.triangles, 4);
  const int n = sphere.vertexCount();
  sphere.triangles.emplace_back(0, 1, n);
  sphere.triangles.emplace_back(-1, 2, 3);
  sphere.triangles.emplace_back(0, n + 1000000, 2);
  with_bad.render(camera, sphere.positions, sphere.triangles, 4);
  EXPECT_EQ(with_bad.depths(), whole.depths());
}

}  // namespace
}  // namespace lumistage
