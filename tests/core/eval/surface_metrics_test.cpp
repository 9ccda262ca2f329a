// Distances to a surface: the grid against brute force, and the truth files.
#include "core/eval/surface_metrics.h"

#include <gtest/gtest.h>

#include <fstream>
#include <random>

#include "core/body/ply_mesh.h"
#include "tests/core/refine/refine_test_scene.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

TEST(SurfaceDistance, MatchesAKnownSphereAndBruteForce) {
  const Eigen::Vector3d centre(0.2, -0.1, 1.0);
  const TriangleMesh sphere = testing::icosphere(centre, 0.5, 4);
  const SurfaceDistance surface(sphere);
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0, 1);
  std::uniform_real_distribution<double> r(0.3, 0.9);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d dir = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    const double radius = i < 190 ? r(rng) : 3.0;  // a few far away (outside the grid)
    const Eigen::Vector3d p = centre + radius * dir;
    // A fine icosphere is within a millimetre of its sphere.
    EXPECT_NEAR(surface.distance(p), std::abs(radius - 0.5), 0.002) << radius;
  }
  // On the surface's vertices: zero.
  EXPECT_NEAR(surface.distance(sphere.positions.col(17).cast<double>()), 0.0, 1e-6);
  Eigen::Matrix3Xf points(3, 2);
  points.col(0) = (centre + Eigen::Vector3d(0.51, 0, 0)).cast<float>();
  points.col(1) = (centre + Eigen::Vector3d(0, 0, 0.47)).cast<float>();
  const SurfaceError e = surfaceError(points, surface);
  EXPECT_NEAR(e.mean_mm, 20.0, 2.0);
  EXPECT_NEAR(e.max_mm, 30.0, 1.5);
}

TEST(SurfaceDistance, BestOffsetsReachTheSurfaceWithinTheRangeOnly) {
  // A coarse sphere of 0.3 m in a true one of 0.32 m: every vertex reaches it 2 cm out; in a true
  // one of 0.36 m it stops at the range's 4 cm, where nothing closer lies on its line.
  const Eigen::Vector3d centre(0.1, 0.2, 1.0);
  const TriangleMesh coarse = testing::icosphere(centre, 0.3, 2);
  for (const auto& [radius, expected] : {std::pair{0.32, 0.32}, std::pair{0.36, 0.34}}) {
    const SurfaceDistance truth(testing::icosphere(centre, radius, 5));
    Eigen::Matrix3Xf moved;
    nearestOffsetsAlongNormals(coarse.positions, coarse.normals, truth, 0.04, 0.04, 0.0005, moved);
    ASSERT_EQ(moved.cols(), coarse.positions.cols());
    for (Eigen::Index v = 0; v < moved.cols(); ++v)
      ASSERT_NEAR((moved.col(v).cast<double>() - centre).norm(), expected, 0.001) << v;
  }
}

TEST(SurfaceDistance, ReadsTruthSurfacesAndRefusesBrokenOnes) {
  const auto folder = testing::testFolder("surface");
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float "
      "y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  std::string body(3 * 12 + 13, '\0');
  const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::memcpy(body.data(), v, 36);
  body[36] = 3;
  const int f[3] = {0, 1, 2};
  std::memcpy(body.data() + 37, f, 12);
  std::ofstream(folder / "ok.ply", std::ios::binary) << header << body;
  const TriangleMesh mesh = readPlyMesh(folder / "ok.ply");
  ASSERT_EQ(mesh.vertexCount(), 3);
  ASSERT_EQ(mesh.triangles.size(), 1u);
  EXPECT_NEAR(SurfaceDistance(mesh).distance({0.2, 0.2, 0.5}), 0.5, 1e-9);
  std::ofstream(folder / "short.ply", std::ios::binary) << header << body.substr(0, 40);
  EXPECT_NE(testing::errorOf([&] { readPlyMesh(folder / "short.ply"); }).find("short.ply"),
            std::string::npos);
  // A vertex count whose size in bytes wraps around to a small one: refused, not allocated.
  std::string huge = header;
  huge.replace(huge.find("vertex 3"), 8, "vertex 1537228672809129302");
  std::ofstream(folder / "huge.ply", std::ios::binary) << huge << body;
  EXPECT_EQ(testing::errorOf([&] { readPlyMesh(folder / "huge.ply"); }),
            (folder / "huge.ply").string() + ": shorter than its header says");
}

}  // namespace
}  // namespace lumistage
