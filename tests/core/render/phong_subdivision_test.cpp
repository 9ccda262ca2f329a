// Phong subdivision: the curved surface through a coarse mesh's vertices and normals.
#include "core/render/phong_subdivision.h"

#include <gtest/gtest.h>

#include "core/body/skinned_mesh.h"
#include "tests/core/refine/refine_test_scene.h"

namespace lumistage {
namespace {

// Each triangle becomes four, closed and wound as before; the coarse vertices keep their indices,
// and the middles of a sphere's edges come out much nearer the sphere than the flat edges' middles.
TEST(PhongSubdivision, LiftsTheEdgesOfACoarseSphereOntoIt) {
  const Eigen::Vector3d centre(0.2, -0.1, 1.0);
  const double radius = 0.3;
  const TriangleMesh sphere = testing::icosphere(centre, radius, 1);  // 42 vertices, 120 edges
  PhongSubdivision phong;
  phong.subdivide(sphere.positions, sphere.normals, sphere.triangles);
  const int n = sphere.vertexCount();
  ASSERT_EQ(phong.positions().cols(), n + 120);
  ASSERT_EQ(phong.normals().cols(), n + 120);
  ASSERT_EQ(phong.triangles().size(), 4 * sphere.triangles.size());
  EXPECT_TRUE(phong.positions().leftCols(n).isApprox(sphere.positions));
  TriangleMesh fine{phong.positions(), phong.normals(), phong.triangles()};
  EXPECT_EQ(checkClosedManifold(fine).error(), "");
  // Wound as the coarse mesh: the recomputed normals point the way the given ones do.
  fine.computeNormals();
  double worst_flat = 0, worst_curved = 0;
  const Eigen::Vector3f c = centre.cast<float>();
  for (Eigen::Index v = n; v < phong.positions().cols(); ++v) {
    EXPECT_GT(fine.normals.col(v).dot(phong.normals().col(v)), 0.9f) << v;
    EXPECT_NEAR(phong.normals().col(v).norm(), 1.0f, 1e-5f);
    const double curved = std::abs((phong.positions().col(v) - c).norm() - radius);
    worst_curved = std::max(worst_curved, curved);
  }
  for (const Eigen::Vector3i& t : sphere.triangles) {
    const Eigen::Vector3f flat = 0.5f * (sphere.positions.col(t[0]) + sphere.positions.col(t[1]));
    worst_flat = std::max(worst_flat, radius - double((flat - c).norm()));
  }
  std::printf("  middles off the sphere: flat %.2f mm, Phong %.2f mm\n", 1e3 * worst_flat,
              1e3 * worst_curved);
  EXPECT_GT(worst_flat, 0.01);              // 19 cm edges: their middles lie 1.5 cm inside
  EXPECT_LT(worst_curved, worst_flat / 2);  // 0.75 of the way to full Phong
}

// A middle keeps only the cameras that see both its ends; a flat mesh stays flat; new triangles
// (another mesh of the same size) are followed.
TEST(PhongSubdivision, MiddlesAreSeenByTheCamerasThatSeeBothEndsAndFlatStaysFlat) {
  Eigen::Matrix3Xf positions(3, 4), normals(3, 4);
  positions << 0, 1, 1, 0,  //
      0, 0, 1, 1,           //
      0, 0, 0, 0;
  normals.setZero();
  normals.row(2).setOnes();
  std::vector<Eigen::Vector3i> square = {{0, 1, 2}, {0, 2, 3}};
  const std::vector<CameraMask> masks = {0b0111, 0b0011, 0b0110, 0b1000};
  PhongSubdivision phong;
  phong.subdivide(positions, normals, square, masks);
  ASSERT_EQ(phong.positions().cols(), 4 + 5);  // 5 edges: four sides and the diagonal
  ASSERT_EQ(phong.masks().size(), 9u);
  for (Eigen::Index v = 4; v < 9; ++v) EXPECT_FLOAT_EQ(phong.positions()(2, v), 0.0f);
  // Find each middle by where it lies.
  const auto maskAt = [&](float x, float y) {
    for (Eigen::Index v = 4; v < 9; ++v)
      if (std::abs(phong.positions()(0, v) - x) < 1e-6f &&
          std::abs(phong.positions()(1, v) - y) < 1e-6f)
        return int(phong.masks()[size_t(v)]);
    return -1;
  };
  EXPECT_EQ(maskAt(0.5f, 0.0f), 0b0011);  // 0 and 1
  EXPECT_EQ(maskAt(1.0f, 0.5f), 0b0010);  // 1 and 2
  EXPECT_EQ(maskAt(0.5f, 0.5f), 0b0110);  // 0 and 2 (the diagonal)
  EXPECT_EQ(maskAt(0.5f, 1.0f), 0b0000);  // 2 and 3
  EXPECT_EQ(maskAt(0.0f, 0.5f), 0b0000);  // 3 and 0
  // The other diagonal: the same sizes, other triangles.
  square = {{0, 1, 3}, {1, 2, 3}};
  phong.subdivide(positions, normals, square, masks);
  EXPECT_EQ(maskAt(0.5f, 0.5f), 0b0000);  // 1 and 3
  // Without masks, none.
  phong.subdivide(positions, normals, square);
  EXPECT_TRUE(phong.masks().empty());
}

}  // namespace
}  // namespace lumistage
