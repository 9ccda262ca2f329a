// The order a mesh is drawn in: the same triangles, wound the same way, in compact patches.
#include "core/render/draw_order.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <set>

#include "core/body/skinned_mesh.h"
#include "tests/core/refine/refine_test_scene.h"

namespace lumistage {
namespace {

// A triangle as its smallest index first, the winding kept (a rotation, not a sort).
Eigen::Vector3i canonical(const Eigen::Vector3i& t) {
  int first = 0;
  for (int k = 1; k < 3; ++k)
    if (t[k] < t[first]) first = k;
  return {t[first], t[(first + 1) % 3], t[(first + 2) % 3]};
}

// Distinct vertices in each run of `window` consecutive triangles, averaged: what a batch of
// vertex shading would hold.
double verticesPerWindow(const std::vector<Eigen::Vector3i>& triangles, int window) {
  double total = 0;
  int windows = 0;
  for (size_t begin = 0; begin + window <= triangles.size(); begin += window, ++windows) {
    std::set<int> used;
    for (size_t t = begin; t < begin + window; ++t)
      for (int k = 0; k < 3; ++k) used.insert(triangles[t][k]);
    total += double(used.size());
  }
  return windows > 0 ? total / windows : 0.0;
}

// Every triangle once, wound as before, through a permutation of the vertices; the mesh stays
// closed; patches are compact where the given order was scattered.
TEST(DrawOrder, DrawsEveryTriangleOnceWoundAsBeforeInCompactPatches) {
  TriangleMesh sphere = testing::icosphere(Eigen::Vector3d(0, 0, 1), 0.3, 4);  // 5120 triangles
  const int n = sphere.vertexCount();
  std::mt19937 random(7);
  std::shuffle(sphere.triangles.begin(), sphere.triangles.end(), random);
  DrawOrder order;
  order.build(n, sphere.triangles);

  std::vector<int> sorted = order.order();
  std::sort(sorted.begin(), sorted.end());
  std::vector<int> all(n);
  std::iota(all.begin(), all.end(), 0);
  ASSERT_EQ(sorted, all);
  ASSERT_EQ(order.triangles().size(), sphere.triangles.size());
  std::multiset<std::array<int, 3>> given, drawn;
  for (const Eigen::Vector3i& t : sphere.triangles) {
    const Eigen::Vector3i c = canonical(t);
    given.insert({c[0], c[1], c[2]});
  }
  for (const Eigen::Vector3i& t : order.triangles()) {
    const Eigen::Vector3i c =
        canonical(Eigen::Vector3i(order.order()[t[0]], order.order()[t[1]], order.order()[t[2]]));
    drawn.insert({c[0], c[1], c[2]});
  }
  EXPECT_EQ(drawn, given);
  TriangleMesh reordered;
  reordered.positions.resize(3, n);
  for (int i = 0; i < n; ++i) reordered.positions.col(i) = sphere.positions.col(order.order()[i]);
  reordered.triangles = order.triangles();
  reordered.computeNormals();
  EXPECT_EQ(checkClosedManifold(reordered).error(), "");

  // A run of 64 triangles of a compact patch uses about 57 vertices; scattered, about 187.
  const double scattered = verticesPerWindow(sphere.triangles, 64);
  const double patched = verticesPerWindow(order.triangles(), 64);
  std::printf("  vertices a run of 64 triangles uses: given %.1f, drawn %.1f\n", scattered,
              patched);
  EXPECT_LT(patched, 0.5 * scattered);
  // The first use of each vertex comes in number order.
  int next = 0;
  for (const Eigen::Vector3i& t : order.triangles())
    for (int k = 0; k < 3; ++k) {
      EXPECT_LE(t[k], next);
      if (t[k] == next) ++next;
    }
}

// Triangles with an index out of range are left out; vertices no triangle uses are numbered last;
// new triangles for the same vertex count are followed.
TEST(DrawOrder, LeavesOutBadTrianglesAndFollowsNewOnes) {
  const std::vector<Eigen::Vector3i> triangles = {{0, 1, 2}, {2, 1, 7}, {-1, 0, 1}, {3, 2, 1}};
  DrawOrder order;
  order.build(5, triangles);
  ASSERT_EQ(order.triangles().size(), 2u);
  ASSERT_EQ(order.order().size(), 5u);
  EXPECT_EQ(order.order()[4], 4);  // unused: last
  const std::vector<Eigen::Vector3i> other = {{4, 3, 0}};
  order.build(5, other);
  ASSERT_EQ(order.triangles().size(), 1u);
  EXPECT_EQ(order.order()[order.triangles()[0][0]], 4);
  EXPECT_EQ(order.order()[order.triangles()[0][1]], 3);
  EXPECT_EQ(order.order()[order.triangles()[0][2]], 0);
}

}  // namespace
}  // namespace lumistage
