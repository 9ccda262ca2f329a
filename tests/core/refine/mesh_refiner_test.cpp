// The refinement module: each term of the error alone, and the whole against a known shape.
#include "core/refine/mesh_refiner.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "core/geometry/ring_rig.h"
#include "core/refine/refinement_sampler.h"
#include "tests/core/refine/ellipsoid_scene.h"
#include "tests/core/refine/refine_test_scene.h"

namespace lumistage {
namespace {

using testing::EllipsoidScene;

// A config whose terms are all off: a test switches on the one it looks at.
// The tests below place their samples on a range as far in as out, 21 offsets, 0 at offset 10.
RefineConfig noTerms() {
  RefineConfig c;
  c.offset_count = 21;
  c.t_inward_m = c.t_max_m;
  c.outside_weight = c.outward_weight = c.colour_weight = c.smooth_weight = c.temporal_weight = 0;
  c.off_contour_outward_weight = c.contour_weight = 0;
  c.tie_margin = 0;
  c.smooth_reference_vertices = 0;  // the tests' few vertices: weights as given
  return c;
}

// One vertex, no neighbours.
struct OneVertex {
  RefinementStatistics stats;
  explicit OneVertex(const RefineConfig& c) { stats.reset(1, c.offset_count, c.colour_bits); }
  // Colour samples: `cameras` cameras seeing grey level `level` plus a per-camera spread.
  void colour(int offset, int cameras, int level, int spread) {
    for (int k = 0; k < cameras; ++k) {
      const uint32_t q = uint32_t(std::clamp(level + (k % 2 ? spread : -spread), 0, 255)) >> 2;
      stats.colour_count[offset]++;
      for (int ch = 0; ch < 3; ++ch) stats.sums[3 * offset + ch] += uint16_t(q);
      stats.squares[offset] += 3 * q * q;
    }
  }
};

// Levels a step, and half a step (RefineConfig::offsetLevels()).
constexpr int kStep = RefineConfig::kLevelsPerStep, kHalf = kStep / 2;

// The chosen offset level: kStep x the offset index, moved where the silhouette crosses next to it.
int refineOne(const RefineConfig& config, const RefinementStatistics& stats) {
  MeshRefiner refiner(config, 1, {});
  std::vector<uint8_t> offsets;
  EXPECT_TRUE(refiner.refine(stats, offsets));
  return offsets.at(0);
}

TEST(MeshRefiner, HullTermAloneMovesAnOutsideVertexInToTheHull) {
  RefineConfig c = noTerms();
  c.outside_weight = 1;
  OneVertex one(c);
  // The hull's surface lies 4 steps inward: offsets beyond are outside some silhouettes, more of
  // them the further out.
  for (int i = 6; i < c.offset_count; ++i) one.stats.outside[i] = uint8_t(1 + (i - 6) / 4);
  // Offset 5, the last inside; the silhouette crosses between 5 and 6, where no node located its
  // edge: halfway.
  EXPECT_EQ(refineOne(c, one.stats), kStep * 5 + kHalf);
  // Where the nodes located the edge, there, to the nearest level: a quarter of the way, two
  // eighths past sample 5; all the way, on sample 6; none of it, on sample 5.
  one.stats.edges[5] = uint8_t(1 + RefinementStatistics::kEdgeLevels / 4);
  EXPECT_EQ(refineOne(c, one.stats), kStep * 5 + kStep / 4);
  one.stats.edges[5] = 1 + RefinementStatistics::kEdgeLevels;
  EXPECT_EQ(refineOne(c, one.stats), kStep * 6);
  one.stats.edges[5] = 1;
  EXPECT_EQ(refineOne(c, one.stats), kStep * 5);
}

TEST(MeshRefiner, OutwardTermAloneFavoursLargeOffsets) {
  RefineConfig c = noTerms();
  c.outward_weight = c.off_contour_outward_weight = 1;
  OneVertex one(c);
  EXPECT_EQ(refineOne(c, one.stats), kStep * (c.offset_count - 1));
  // With the hull: as far out as the hull allows, half a step beyond the last sample inside.
  c.outside_weight = 1;
  for (int i = 15; i < c.offset_count; ++i) one.stats.outside[i] = 2;
  EXPECT_EQ(refineOne(c, one.stats), kStep * 14 + kHalf);
  EXPECT_NEAR(c.levelOffset(kStep * 14 + kHalf), (c.offsetAt(14) + c.offsetAt(15)) / 2, 1e-12);
}

TEST(MeshRefiner, AColourMinimumBetweenTwoSamplesTakesTheHalfStep) {
  RefineConfig c = noTerms();
  c.colour_weight = 1;
  // The cameras agree best at offset 13; how well at 12 and 14 says on which side of 13 the
  // surface lies: much better at 14 than at 12, the parabola's lowest point is more than a
  // quarter step outward, half a step out; equally well, at 13.
  const auto level = [&](int spread_12, int spread_14) {
    OneVertex one(c);
    for (int i = 0; i < c.offset_count; ++i)
      one.colour(i, 4, 120, i == 13 ? 4 : (i == 12 ? spread_12 : (i == 14 ? spread_14 : 40)));
    return refineOne(c, one.stats);
  };
  EXPECT_EQ(level(40, 8), kStep * 13 + kHalf);
  EXPECT_EQ(level(8, 40), kStep * 13 - kHalf);
  EXPECT_EQ(level(20, 20), kStep * 13);
  EXPECT_EQ(level(20, 18), kStep * 13);  // a little better outward: within a quarter step of 13
}

TEST(MeshRefiner, ColourTermAloneFindsTheConsistentOffset) {
  RefineConfig c = noTerms();
  c.colour_weight = 1;
  OneVertex one(c);
  for (int i = 0; i < c.offset_count; ++i) one.colour(i, 4, 120, i == 13 ? 1 : 40);
  EXPECT_EQ(refineOne(c, one.stats), kStep * 13);
  {  // The refiner's fast path computes what dataError() says.
    MeshRefiner refiner(c, 1, {});
    std::vector<uint8_t> offsets;
    ASSERT_TRUE(refiner.refine(one.stats, offsets));
    for (int i = 0; i < c.offset_count; ++i)
      EXPECT_NEAR(refiner.dataErrors()[i], refiner.dataError(one.stats, i, i), 1e-5) << i;
  }
  // A point outside the hull has no colour consistency, whatever the colours say.
  one.stats.outside[13] = 1;
  one.stats.dropOutside();
  EXPECT_NE(refineOne(c, one.stats) / kStep, 13);
}

// With window points (the vertex, then its two neighbours on the tangent plane, as the sampler
// lays them out), a sample's colour term is the mean over the points: where the vertex's own pixel
// agrees at two offsets equally, the window picks the one where its neighbours agree too; a point
// outside the hull or seen by fewer than two cameras has no say; statistics of another layout
// are refused.
TEST(MeshRefiner, WindowPointsDecideWhereTheVertexAloneIsAmbiguous) {
  RefineConfig c = noTerms();
  c.colour_weight = 1;
  const int m = c.offset_count;
  RefinementStatistics window;
  window.reset(3, m, c.colour_bits);
  // Point p's sample i is sample p * m + i (one vertex: a point's block is m samples long).
  const auto colour = [&](int point, int i, int spread) {
    OneVertex one(c);
    one.colour(i, 4, 120, spread);
    const size_t s = size_t(point) * m + i;
    window.colour_count[s] = one.stats.colour_count[i];
    for (int ch = 0; ch < 3; ++ch) window.sums[3 * s + ch] = one.stats.sums[3 * i + ch];
    window.squares[s] = one.stats.squares[i];
  };
  for (int i = 0; i < m; ++i) {
    colour(0, i, (i == 6 || i == 14) ? 1 : 40);  // the vertex: two offsets agree, 4 from zero each
    colour(1, i, i == 14 ? 1 : 40);              // its neighbours agree at 14 only
    colour(2, i, i == 14 ? 1 : 40);
  }
  RefinementStatistics alone;
  alone.reset(1, m, c.colour_bits);
  std::copy_n(window.colour_count.begin(), m, alone.colour_count.begin());
  std::copy_n(window.sums.begin(), 3 * m, alone.sums.begin());
  std::copy_n(window.squares.begin(), m, alone.squares.begin());
  EXPECT_EQ(refineOne(c, alone), kStep * 6);    // a tie: the first of the two
  EXPECT_EQ(refineOne(c, window), kStep * 14);  // the window's
  {  // The fast path computes what dataError() says, window included.
    MeshRefiner refiner(c, 1, {});
    std::vector<uint8_t> offsets;
    ASSERT_TRUE(refiner.refine(window, offsets));
    for (int i = 0; i < m; ++i)
      EXPECT_NEAR(refiner.dataErrors()[i], refiner.dataError(window, i, i), 1e-5) << i;
  }
  // The neighbours outside the hull (or unseen) at 14 and agreeing at 6: the vertex's own
  // agreement at 14 is then the whole mean there, and 6 is as good: the tie again.
  for (const int point : {1, 2}) {
    window.outside[size_t(point) * m + 14] = point == 1 ? 1 : 0;
    window.colour_count[size_t(point) * m + 14] = point == 2 ? 1 : window.colour_count[14];
    colour(point, 6, 1);
  }
  window.dropOutside();
  EXPECT_EQ(refineOne(c, window), kStep * 6);
  RefinementStatistics two;
  two.reset(2, m, c.colour_bits);
  MeshRefiner refiner(c, 1, {});
  std::vector<uint8_t> offsets;
  EXPECT_FALSE(refiner.refine(two, offsets));
}

TEST(MeshRefiner, TieBreakTakesTheMinimumClosestToZero) {
  RefineConfig c = noTerms();
  c.colour_weight = 1;
  c.tie_margin = 0.05;
  OneVertex one(c);
  // Two consistent offsets (the paper's Fig. 3: the torso at 8, the arm at 18).
  for (int i = 0; i < c.offset_count; ++i) one.colour(i, 4, 120, (i == 8 || i == 18) ? 1 : 40);
  EXPECT_EQ(refineOne(c, one.stats), kStep * 8);
  // The far one is much better than the margin: it wins.
  one.stats.reset(1, c.offset_count, c.colour_bits);
  for (int i = 0; i < c.offset_count; ++i) one.colour(i, 4, 120, i == 18 ? 0 : (i == 8 ? 12 : 40));
  EXPECT_EQ(refineOne(c, one.stats), kStep * 18);
  // On a range reaching 2 cm in and 8 cm out, 0 is offset 4: of two consistent offsets, 1 (three
  // steps in) wins over 8 (four steps out), though 8 is nearer the range's middle.
  c.t_inward_m = 0.02, c.t_max_m = 0.08;
  ASSERT_EQ(c.zeroOffsetIndex(), 4);
  one.stats.reset(1, c.offset_count, c.colour_bits);
  for (int i = 0; i < c.offset_count; ++i) one.colour(i, 4, 120, (i == 1 || i == 8) ? 1 : 40);
  EXPECT_EQ(refineOne(c, one.stats), kStep * 1);
}

TEST(MeshRefiner, ASilhouetteCrossingInwardMovesHalfAStepIn) {
  RefineConfig c = noTerms();
  c.colour_weight = 1;
  c.outside_weight = 1;
  OneVertex one(c);
  // The colours agree best at offset 3, just inside; offsets 0 to 2 fall outside a silhouette
  // (a point on the far side of a thin limb): the surface lies between 2 and 3.
  for (int i = 0; i < c.offset_count; ++i) one.colour(i, 4, 120, i == 3 ? 1 : 40);
  for (int i = 0; i < 3; ++i) one.stats.outside[i] = 1;
  one.stats.dropOutside();
  EXPECT_EQ(refineOne(c, one.stats), kStep * 3 - kHalf);
}

// The contour term: where a camera sees the vertex on its contour, the hull's crossing is the
// surface, and a colour term a little higher at the last sample inside (the screen's spill on the
// rim) no longer takes the vertex a step in; elsewhere it still does.
TEST(MeshRefiner, TheContourTermTakesAContourVertexToTheHull) {
  RefineConfig c = noTerms();
  c.outside_weight = c.colour_weight = 1;
  c.contour_weight = 0.6;
  OneVertex one(c);
  for (int i = 15; i < c.offset_count; ++i) one.stats.outside[i] = 1;
  for (int i = 0; i < 15; ++i) one.colour(i, 4, 120, i == 13 ? 0 : (i == 14 ? 20 : 40));
  // Sample 13 agrees best; 14, the last inside, a little less.
  EXPECT_EQ(refineOne(c, one.stats), kStep * 13);
  MeshRefiner refiner(c, 1, {});
  const float inside = refiner.dataError(one.stats, 14, 14);
  EXPECT_GT(inside, 0.3f);
  one.stats.contour[0] = 1;
  // On a contour: the last sample inside, moved to the hull's edge (none located: halfway).
  EXPECT_EQ(refineOne(c, one.stats), kStep * 14 + kHalf);
  EXPECT_FLOAT_EQ(refiner.dataError(one.stats, 14, 14), inside - 0.6f);
  EXPECT_FLOAT_EQ(refiner.dataError(one.stats, 13, 13), 0.0f);  // only the last inside
  // A weaker term than the colour's difference leaves the choice to the colours: sample 13, though
  // the error's parabola through it and its neighbours now leans half a step toward the hull.
  c.contour_weight = 0.3;
  EXPECT_EQ(refineOne(c, one.stats), kStep * 13 + kHalf);
}

// The outward term pulls a vertex that a camera sees on its contour, where the hull touches the
// surface, harder than one off every contour (between the legs, under the arms), where the hull is
// only a bound on it and a colour minimum inside it may be the surface.
TEST(MeshRefiner, TheOutwardTermHoldsAVertexOffTheContoursLess) {
  RefineConfig c = noTerms();
  c.outside_weight = 3;
  c.colour_weight = 1;
  c.outward_weight = 2;
  c.off_contour_outward_weight = 0.5;
  OneVertex one(c);
  for (int i = 15; i < c.offset_count; ++i) one.stats.outside[i] = 1;
  for (int i = 0; i < 15; ++i) one.colour(i, 4, 120, i == 10 ? 8 : 40);
  one.stats.dropOutside();
  EXPECT_EQ(refineOne(c, one.stats), kStep * 10);  // the colours' minimum
  MeshRefiner refiner(c, 1, {});
  const float off = refiner.dataError(one.stats, 14, 14),
              off_at_0 = refiner.dataError(one.stats, 10, 10);
  one.stats.contour[0] = 1;
  EXPECT_EQ(refineOne(c, one.stats), kStep * 14 + kHalf);  // the hull (no edge located: halfway)
  // Sample 14 lies 0.4 of t_max out: the outward term there is 0.4 x 2 against 0.4 x 0.5.
  EXPECT_NEAR(refiner.dataError(one.stats, 14, 14), off - (2 - 0.5) * 0.4, 1e-5);
  EXPECT_FLOAT_EQ(refiner.dataError(one.stats, 10, 10), off_at_0);  // t = 0: no outward term
}

TEST(MeshRefiner, SmoothnessPullsAnAmbiguousVertexToItsNeighbours) {
  RefineConfig c = noTerms();
  c.colour_weight = 1;
  c.smooth_weight = 1;
  c.tie_margin = 0;
  // A fan: vertex 0 in the middle of 6 neighbours that clearly want offset 15; vertex 0's own
  // colours prefer offset 5 by a little.
  std::vector<Eigen::Vector3i> triangles;
  for (int k = 0; k < 6; ++k) triangles.push_back({0, 1 + k, 1 + (k + 1) % 6});
  RefinementStatistics stats;
  stats.reset(7, c.offset_count, c.colour_bits);
  auto colour = [&](int v, int offset, int spread) {
    const size_t s = size_t(v) * c.offset_count + offset;
    for (int k = 0; k < 4; ++k) {
      const uint32_t q = uint32_t(120 + (k % 2 ? spread : -spread)) >> 2;
      stats.colour_count[s]++;
      for (int ch = 0; ch < 3; ++ch) stats.sums[3 * s + ch] += uint16_t(q);
      stats.squares[s] += 3 * q * q;
    }
  };
  for (int i = 0; i < c.offset_count; ++i) {
    colour(0, i, i == 5 ? 8 : (i == 15 ? 10 : 40));
    for (int v = 1; v < 7; ++v) colour(v, i, i == 15 ? 0 : 40);
  }
  std::vector<uint8_t> offsets;
  RefineConfig colour_only = noTerms();
  colour_only.colour_weight = 1;
  MeshRefiner without(colour_only, 7, triangles);
  ASSERT_TRUE(without.refine(stats, offsets));
  EXPECT_EQ(offsets[0], kStep * 5);
  MeshRefiner with(c, 7, triangles);
  ASSERT_TRUE(with.refine(stats, offsets));
  EXPECT_EQ(offsets[0], kStep * 15);
  for (int v = 1; v < 7; ++v) EXPECT_EQ(offsets[v], kStep * 15);
  // The weight follows the mesh's density: set for a mesh of 700 vertices, this fan's 7 take a
  // hundredth of it, and vertex 0 keeps its own colours' offset.
  c.smooth_reference_vertices = 700;
  MeshRefiner sparse(c, 7, triangles);
  ASSERT_TRUE(sparse.refine(stats, offsets));
  EXPECT_EQ(offsets[0], kStep * 5);
}

TEST(MeshRefiner, TemporalTermKeepsAStillVertexWhereItWas) {
  RefineConfig c = noTerms();
  c.colour_weight = 1;
  c.temporal_weight = 0.5;
  MeshRefiner refiner(c, 1, {});
  std::vector<uint8_t> offsets;
  OneVertex first(c);
  for (int i = 0; i < c.offset_count; ++i) first.colour(i, 4, 120, i == 16 ? 1 : 40);
  ASSERT_TRUE(refiner.refine(first.stats, offsets));
  EXPECT_EQ(offsets[0], kStep * 16);
  // Next frame: noise makes offset 4 look a little better than 16; the vertex stays.
  OneVertex next(c);
  for (int i = 0; i < c.offset_count; ++i) next.colour(i, 4, 120, i == 4 ? 2 : (i == 16 ? 4 : 40));
  ASSERT_TRUE(refiner.refine(next.stats, offsets));
  EXPECT_EQ(offsets[0], kStep * 16);
  // Without the previous frame, it would have jumped.
  refiner.resetTemporal();
  ASSERT_TRUE(refiner.refine(next.stats, offsets));
  EXPECT_EQ(offsets[0], kStep * 4);
}

TEST(MeshRefiner, RefusesStatisticsOfAnotherMesh) {
  RefineConfig c;
  MeshRefiner refiner(c, 10, {});
  RefinementStatistics stats;
  stats.reset(11, c.offset_count, c.colour_bits);
  std::vector<uint8_t> offsets(3, 7);
  EXPECT_FALSE(refiner.refine(stats, offsets));
  EXPECT_EQ(offsets, std::vector<uint8_t>(3, 7));
}

// The whole: an icosphere inside a textured ellipsoid, 12 cameras, converges onto the ellipsoid.
TEST_F(EllipsoidScene, AnInnerSphereConvergesOntoTheShape) {
  const TriangleMesh sphere = testing::icosphere(shape_.centre, 0.25, 3);  // 642 vertices
  RefineConfig config;
  config.t_max_m = 0.09;
  config.depth_map_step = 4;
  std::vector<int> all;
  for (int c = 0; c < rig_->cameraCount(); ++c) all.push_back(c);
  RefinementSampler sampler(config);
  RefinementStatistics stats;
  sampler.sample(cameras(all), sphere.positions, sphere.normals, sphere.triangles, stats);
  MeshRefiner refiner(config, sphere.vertexCount(), sphere.triangles);
  std::vector<uint8_t> offsets;
  ASSERT_TRUE(refiner.refine(stats, offsets));
  Eigen::Matrix3Xf refined;
  applyOffsets(config, offsets, sphere.positions, sphere.normals, refined);
  const auto [before, before_worst] = error(sphere.positions);
  const auto [after, after_worst] = error(refined);
  EXPECT_GT(before, 0.04);
  // The offsets are 9 mm apart: within a step on average, a few steps at worst (where two
  // cameras agree by chance inside the shape).
  EXPECT_LT(after, 0.006) << "before " << before;
  EXPECT_LT(after_worst, 0.035);
}

}  // namespace
}  // namespace lumistage
