// The refinement's sampler: where it locates the silhouettes' edges, how it reads the actor's
// colours, and what the nodes' statistics add up to, against a scene whose truth is known.
#include "core/refine/refinement_sampler.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "core/geometry/ring_rig.h"
#include "core/refine/mesh_refiner.h"
#include "tests/core/refine/ellipsoid_scene.h"
#include "tests/core/refine/refine_test_scene.h"

namespace lumistage {
namespace {

using testing::EllipsoidScene;

// The nodes locate each silhouette's edge below a pixel (RefinementStatistics::edges): on images
// whose pixels mix the actor's and the screen's colours at the edges, as a sensor's do, the
// located edges lie far nearer the hull's true surface (each camera's ray grazing the ellipsoid)
// than halfway between the samples they fall between.
TEST(RefinementSampler, LocatesTheHullsEdgeBelowAPixel) {
  const testing::Ellipsoid shape;
  const Rig rig = testing::smallRing();
  const std::vector<Image> images = testing::renderEllipsoid(rig, shape, 4);
  const GreenScreenKeyer keyer;
  std::vector<SamplerCamera> cameras;
  for (int c = 0; c < rig.cameraCount(); ++c)
    cameras.push_back({&rig.camera(c), images[c].view(), &keyer, nullptr});
  const TriangleMesh sphere = testing::icosphere(shape.centre, 0.28, 2);  // 162 vertices
  RefineConfig config;
  config.t_max_m = 0.09;
  config.depth_map_step = 4;
  config.window_points = 1;
  RefinementSampler sampler(config);
  RefinementStatistics stats;
  sampler.sample(cameras, sphere.positions, sphere.normals, sphere.triangles, stats);
  const testing::EdgeDistances e = testing::hullEdgeDistances(rig, shape, sphere, config, stats);
  const int edges = e.edges, leaving = e.leaving;
  const double located = e.located, halfway = e.halfway;
  ASSERT_GT(edges, 100) << leaving << " samples where the hull leaves";
  EXPECT_GT(edges, leaving * 9 / 10);
  // A step is 9 mm, 1.5 pixels at the ellipsoid: halfway misses by a quarter step on average, the
  // located edges by less than a sixth of a pixel (0.8 mm against 2.3 when written).
  EXPECT_GT(halfway, 0.0015);
  EXPECT_LT(located, 0.001);
  EXPECT_LT(located, 0.4 * halfway) << "located " << located << " m, halfway " << halfway << " m";
}

// Calls f(s, v, i, u) for every sample s (vertex v of `mesh`, offset i) that `camera` coloured, u
// the column its point projects to.
template <typename F>
void forEachColouredSample(const RefinementStatistics& stats, const RefineConfig& config,
                           const TriangleMesh& mesh, const Camera& camera, F&& f) {
  for (int v = 0; v < mesh.vertexCount(); ++v) {
    for (int i = 0; i < config.offset_count; ++i) {
      const size_t s = size_t(v) * config.offset_count + i;
      if (stats.colour_count[s] == 0) continue;
      const Eigen::Vector3d p = mesh.positions.col(v).cast<double>() +
                                config.offsetAt(i) * mesh.normals.col(v).cast<double>();
      f(s, v, i, camera.project(p)->x());
    }
  }
}

// A configuration whose statistics hold each camera's colour at a vertex as it read it: 8 bits a
// channel, no window points.
RefineConfig exactColours() {
  RefineConfig config;
  config.colour_bits = 8;
  config.window_points = 1;
  return config;
}

// Calls f(bayer, cameras) with the camera filming `rgba` as an RGB image, then as a Bayer one,
// keyed by `keyer`.
template <typename F>
void forEachFormat(const std::vector<uint8_t>& rgba, const Camera& camera,
                   const GreenScreenKeyer& keyer, F&& f) {
  for (const PixelFormat format : {PixelFormat::kRgb8, PixelFormat::kBayerRggb8}) {
    SCOPED_TRACE(format == PixelFormat::kRgb8 ? "rgb8" : "bayer");
    Image image;
    rgbaToImage(rgba.data(), camera.width(), camera.height(), format, image);
    f(format != PixelFormat::kRgb8,
      std::vector<SamplerCamera>{{&camera, image.view(), &keyer, nullptr}});
  }
}

// A point's colour is read between pixels (bilinear), from the pixels keyed as the actor only: on
// an image whose red rises 4 levels a pixel to the right, the statistics hold each sample's red
// as its projection's column gives it, not its nearest pixel's (up to 2 levels off, 4 between a
// Bayer image's cells); and beside the silhouette's edge, the screen's colour never enters a
// sample's. On Bayer the colours are the 2x2 cells' (red at a cell's first column, half a pixel
// left of its centre). The key too is read between pixels: a sample is the actor's up to where
// the green excess interpolated between the last actor pixel (cell) and the first screen one
// reaches the key's threshold, and no further.
TEST(RefinementSampler, ReadsTheActorsColourBetweenPixels) {
  const Rig rig = testing::smallRing();
  const Camera& camera = rig.camera(0);
  const Eigen::Vector3d centre(0, 0, 1.1);
  const Eigen::Vector2d middle = *camera.project(centre);
  // The actor left of the edge, the screen right of it; an even column, so that no Bayer cell
  // holds both.
  const int edge_x = 2 * ((int(std::lround(middle.x())) + 12) / 2);
  const auto red = [&](double x) { return std::clamp(4.0 * (x - middle.x()) + 128.0, 0.0, 255.0); };
  std::vector<uint8_t> rgba(size_t(camera.width()) * camera.height() * 4);
  for (int y = 0; y < camera.height(); ++y) {
    for (int x = 0; x < camera.width(); ++x) {
      uint8_t* q = &rgba[4 * (size_t(y) * camera.width() + x)];
      if (x < edge_x) {
        q[0] = uint8_t(std::lround(red(x))), q[1] = 60, q[2] = 120;
      } else {
        q[0] = 40, q[1] = 200, q[2] = 60;
      }
      q[3] = 255;
    }
  }
  const GreenScreenKeyer keyer;
  const TriangleMesh sphere = testing::icosphere(centre, 0.2, 3);
  RefineConfig config = exactColours();
  forEachFormat(rgba, camera, keyer, [&](bool bayer, const std::vector<SamplerCamera>& cameras) {
    RefinementSampler sampler(config);
    RefinementStatistics stats;
    sampler.sample(cameras, sphere.positions, sphere.normals, sphere.triangles, stats);
    // The red at pixel position u, as interpolated; and as the nearest pixel (cell) gives it.
    const auto expected = [&](double u) { return red(bayer ? u - 0.5 : u); };
    const auto nearest = [&](double u) {
      const int x = int(std::floor(u + 0.5));
      return red(bayer ? x & ~1 : x);
    };
    // Where the interpolated green excess reaches the threshold: between the centres of the last
    // actor pixel (cell) and the first screen one.
    const double last_actor = bayer ? edge_x - 1.5 : edge_x - 1.0, pitch = bayer ? 2 : 1;
    const double actor_excess = 60 - std::max(red(bayer ? edge_x - 2 : edge_x - 1), 120.0);
    const double screen_excess = 200 - 60;
    const double turns =
        last_actor + pitch * (keyer.threshold() - actor_excess) / (screen_excess - actor_excess);
    ASSERT_GT(turns, edge_x - 0.5);  // past where the nearest pixel's key turned
    double interpolated_error = 0, nearest_error = 0, furthest = 0;
    int inner = 0, beside_edge = 0;
    forEachColouredSample(stats, config, sphere, camera, [&](size_t s, int v, int i, double u) {
      furthest = std::max(furthest, u);
      if (u > edge_x - (bayer ? 1.5 : 1.0)) {
        // Its right-hand neighbours are the screen: the colour is the actor's alone.
        ++beside_edge;
        EXPECT_EQ(stats.sums[3 * s + 1], 60) << "vertex " << v << " offset " << i;
        EXPECT_EQ(stats.sums[3 * s + 2], 120);
      } else if (std::abs(u - middle.x()) < 25) {
        ++inner;
        interpolated_error += std::abs(stats.sums[3 * s] - expected(u));
        nearest_error += std::abs(nearest(u) - expected(u));
      }
    });
    ASSERT_LT(furthest, turns + 1e-3) << "a sample keyed as the screen has a colour";
    ASSERT_GT(inner, 200);
    ASSERT_GT(beside_edge, 10);
    EXPECT_GT(furthest, turns - 0.1);  // the key reaches as far as it should
    interpolated_error /= inner, nearest_error /= inner;
    EXPECT_LT(interpolated_error, 0.4) << "nearest pixel: " << nearest_error;
    EXPECT_GT(nearest_error, 0.8);
  });
}

// A pixel (a Bayer cell) the screen covers in part keys as the actor up to the key's threshold,
// its colour mixed with the screen's: a point's colour leaves it out where a pixel the key holds
// well inside the actor is beside it (RefineConfig::colour_purity). The actor is uniform, the
// column (cell) on its edge 40% screen (green excess 20 against the threshold's 30), so every
// colour read between the last actor pixel and that column is the actor's own; with every pixel
// keyed as the actor taken (colour_purity 1) the mix shows.
TEST(RefinementSampler, LeavesPixelsTheScreenCoversInPartOutOfTheColours) {
  const Rig rig = testing::smallRing();
  const Camera& camera = rig.camera(0);
  const Eigen::Vector3d centre(0, 0, 1.1);
  const Eigen::Vector2d middle = *camera.project(centre);
  const int edge_x = 2 * ((int(std::lround(middle.x())) + 12) / 2);  // a Bayer cell's first
  const uint8_t actor[3] = {100, 60, 120}, screen[3] = {40, 200, 60};
  uint8_t mixed[3];
  for (int k = 0; k < 3; ++k) mixed[k] = uint8_t(std::lround(0.6 * actor[k] + 0.4 * screen[k]));
  std::vector<uint8_t> rgba(size_t(camera.width()) * camera.height() * 4);
  for (size_t p = 0; p < size_t(camera.width()) * camera.height(); ++p) {
    const int x = int(p % camera.width());
    const uint8_t* c = x < edge_x ? actor : (x < edge_x + 2 ? mixed : screen);
    std::copy(c, c + 3, &rgba[4 * p]);
    rgba[4 * p + 3] = 255;
  }
  const GreenScreenKeyer keyer;
  ASSERT_TRUE(keyer.isForeground(Rgb{mixed[0], mixed[1], mixed[2]}, 0, 0));
  const TriangleMesh sphere = testing::icosphere(centre, 0.2, 3);
  forEachFormat(rgba, camera, keyer, [&](bool bayer, const std::vector<SamplerCamera>& cameras) {
    // Pixel (cell) centres: the last actor one, and the mixed one.
    const double last_actor = bayer ? edge_x - 1.5 : edge_x - 1.0;
    const double mixed_centre = bayer ? edge_x + 0.5 : edge_x;
    for (const double purity : {0.4, 1.0}) {
      SCOPED_TRACE(purity);
      RefineConfig config = exactColours();
      config.colour_purity = purity;
      RefinementSampler sampler(config);
      RefinementStatistics stats;
      sampler.sample(cameras, sphere.positions, sphere.normals, sphere.triangles, stats);
      int beside = 0, mixed_in = 0;
      forEachColouredSample(stats, config, sphere, camera, [&](size_t s, int v, int i, double u) {
        if (u <= last_actor + 0.05 || u >= mixed_centre - 0.05) return;
        ++beside;
        mixed_in += stats.sums[3 * s + 1] > actor[1];
        if (purity < 1) {
          EXPECT_EQ(stats.sums[3 * s], actor[0]) << "vertex " << v << " offset " << i;
          EXPECT_EQ(stats.sums[3 * s + 1], actor[1]);
          EXPECT_EQ(stats.sums[3 * s + 2], actor[2]);
        }
      });
      ASSERT_GT(beside, 10);
      if (purity == 1) {
        EXPECT_GT(mixed_in, beside / 2);
      } else {
        EXPECT_EQ(mixed_in, 0);
      }
    }
  });
}

// A green-screen camera's colours are despilled as the renderer's are (RefineConfig::despill): the
// green limited to the larger of the red and the blue, since the screen's light spills green on
// the actor's edges in the cameras that see them at a grazing angle and not in the others. A camera
// keyed by a background learnt from the empty stage keeps its colours, and so does every camera
// with the despill off.
TEST(RefinementSampler, DespillsAGreenScreenCamerasColours) {
  const Rig rig = testing::smallRing();
  const Camera& camera = rig.camera(0);
  const uint8_t actor[3] = {100, 120, 90}, screen[3] = {40, 200, 60};  // green excess 20 and 140
  Image image, empty;
  image.resize(PixelFormat::kRgb8, camera.width(), camera.height());
  empty.resize(PixelFormat::kRgb8, camera.width(), camera.height());
  for (size_t p = 0; p < size_t(camera.width()) * camera.height(); ++p) {
    std::copy(actor, actor + 3, &image.pixels[3 * p]);
    std::copy(screen, screen + 3, &empty.pixels[3 * p]);
  }
  const GreenScreenKeyer keyer;
  ASSERT_TRUE(keyer.isForeground(image.view(), 0, 0));
  BackgroundModel background(camera.width(), camera.height());
  background.add(empty.view());
  background.learn();
  ASSERT_TRUE(background.isForeground(image.view(), 0, 0));
  const TriangleMesh sphere = testing::icosphere(Eigen::Vector3d(0, 0, 1.1), 0.2, 2);
  for (const bool despill : {true, false}) {
    for (const bool green_screen : {true, false}) {
      SCOPED_TRACE(::testing::Message()
                   << "despill " << despill << ", green screen " << green_screen);
      RefineConfig config = exactColours();
      config.despill = despill;
      RefinementSampler sampler(config);
      RefinementStatistics stats;
      const std::vector<SamplerCamera> cameras = {{&camera, image.view(),
                                                   green_screen ? &keyer : nullptr,
                                                   green_screen ? nullptr : &background}};
      sampler.sample(cameras, sphere.positions, sphere.normals, sphere.triangles, stats);
      const int green = despill && green_screen ? actor[0] : actor[1];
      int coloured = 0;
      forEachColouredSample(stats, config, sphere, camera, [&](size_t s, int v, int i, double) {
        ++coloured;
        EXPECT_EQ(stats.sums[3 * s], actor[0]) << "vertex " << v << " offset " << i;
        EXPECT_EQ(stats.sums[3 * s + 1], green) << "vertex " << v << " offset " << i;
        EXPECT_EQ(stats.sums[3 * s + 2], actor[2]) << "vertex " << v << " offset " << i;
      });
      EXPECT_GT(coloured, 100);
    }
  }
}

// One mesh of two: a's vertices, then b's.
TriangleMesh joined(const TriangleMesh& a, const TriangleMesh& b) {
  TriangleMesh both;
  both.positions.resize(3, a.vertexCount() + b.vertexCount());
  both.normals.resize(3, a.vertexCount() + b.vertexCount());
  both.positions << a.positions, b.positions;
  both.normals << a.normals, b.normals;
  both.triangles = a.triangles;
  for (const Eigen::Vector3i& t : b.triangles)
    both.triangles.push_back(t.array() + a.vertexCount());
  return both;
}

// Given an earlier frame's offsets (`surface_levels`), the sampler sees the actor through the
// surface they make: a small sphere in front of a large one hides part of it from the camera; the
// offsets that shrink the small sphere to a fifth of its radius uncover what it no longer hides,
// and the samples stay where they were (their colours and keys are the posed mesh's points').
// Offsets of another mesh's size are ignored.
TEST_F(EllipsoidScene, SeesThroughTheSurfaceOfAnEarlierFramesOffsets) {
  const Camera& camera = rig_->camera(0);
  const Eigen::Vector3d ahead = (shape_.centre - camera.centre()).normalized();
  const TriangleMesh large = testing::icosphere(shape_.centre, 0.2, 3);
  const TriangleMesh small = testing::icosphere(shape_.centre - 0.4 * ahead, 0.045, 2);
  const int n = large.vertexCount();
  const TriangleMesh both = joined(large, small);
  RefineConfig config;
  config.depth_map_step = 2;
  config.window_points = 1;
  RefinementSampler sampler(config);
  RefinementStatistics plain, through;
  sampler.sample(cameras({0}), both.positions, both.normals, both.triangles, plain);
  // The large sphere at its own place (level of offset 0), the small one 3.5 cm in.
  std::vector<uint8_t> levels(size_t(both.vertexCount()), uint8_t(config.zeroLevel()));
  std::fill(levels.begin() + n, levels.end(), uint8_t(0));
  ASSERT_NEAR(config.levelOffset(0), -0.035, 1e-9);
  sampler.sample(cameras({0}), both.positions, both.normals, both.triangles, through, levels);
  const auto seen = [&](const RefinementStatistics& stats, int v) {
    return stats.colour_count[size_t(v) * config.offset_count + config.zeroOffsetIndex()] > 0;
  };
  int hidden = 0, uncovered = 0;
  for (int v = 0; v < n; ++v) {
    const double facing = large.normals.col(v).cast<double>().dot(-ahead);
    if (seen(plain, v)) {
      // Nothing came in front (away from the rim, where the map's cells are coarse against the
      // tighter refined_depth_tolerance_m).
      if (facing > 0.5) {
        EXPECT_TRUE(seen(through, v)) << "vertex " << v;
      }
    } else if (facing > 0.9) {
      ++hidden;  // facing the camera, behind the small sphere
      uncovered += seen(through, v);
    }
  }
  ASSERT_GE(hidden, 5);
  EXPECT_GE(uncovered, hidden / 2);
  // The samples are the posed mesh's: where both see a point, its colour and key are the same.
  for (size_t s = 0; s < plain.outside.size(); ++s) {
    EXPECT_EQ(plain.outside[s], through.outside[s]) << "sample " << s;
    if (plain.colour_count[s] > 0 && through.colour_count[s] > 0) {
      EXPECT_EQ(plain.sums[3 * s], through.sums[3 * s]) << "sample " << s;
    }
  }
  // Offsets of another mesh: as none.
  levels.pop_back();
  sampler.sample(cameras({0}), both.positions, both.normals, both.triangles, through, levels);
  EXPECT_EQ(through.colour_count, plain.colour_count);
}

// The sampler projects a vertex's offsets along a parabola through the projections of the
// range's ends and middle: through a strong lens, every sample still lands where the camera's own
// projection puts it (the key alternates from one pixel column to the next, so a projection a
// fraction of a pixel off would flip it), whether the range reaches as far in as out or not.
TEST(RefinementSampler, ProjectsEveryOffsetAsTheCameraDoes) {
  RingRigSpec spec;
  spec.width = 320, spec.height = 240, spec.radius_m = 2.0, spec.vertical_fov_deg = 60;
  spec.distortion = {-0.3, 0.1, 0.002, -0.002, 0.0};
  const Rig rig = makeRingRig(spec);
  const Camera& camera = rig.camera(0);
  Image image;
  image.resize(PixelFormat::kRgb8, camera.width(), camera.height());
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      uint8_t* q = &image.pixels[3 * (size_t(y) * image.width + x)];
      const bool screen = x % 2 == 1;
      q[0] = screen ? 40 : 120, q[1] = screen ? 200 : 110, q[2] = screen ? 60 : 100;
    }
  }
  const GreenScreenKeyer keyer;
  const std::vector<SamplerCamera> cameras = {{&camera, image.view(), &keyer, nullptr}};
  // Off the optical axis, where the lens bends the lines most.
  const TriangleMesh sphere = testing::icosphere(Eigen::Vector3d(0.3, 0.4, 1.3), 0.25, 3);
  for (const double inward : {0.09, 0.02}) {
    RefineConfig config;
    config.t_max_m = 0.09;
    config.t_inward_m = inward;
    config.offset_count = 21;
    config.window_points = 1;
    RefinementSampler sampler(config);
    RefinementStatistics stats;
    sampler.sample(cameras, sphere.positions, sphere.normals, sphere.triangles, stats);
    int compared = 0, different = 0;
    for (int v = 0; v < sphere.vertexCount(); ++v) {
      for (int i = 0; i < config.offset_count; ++i) {
        const Eigen::Vector3d p = sphere.positions.col(v).cast<double>() +
                                  config.offsetAt(i) * sphere.normals.col(v).cast<double>();
        const std::optional<Eigen::Vector2d> pixel = camera.project(p);
        if (!pixel || !camera.inImage(*pixel)) continue;
        ++compared;
        // Keyed between pixels: the actor's within (threshold - actor's excess) / (screen's -
        // actor's) of a pixel of an even column's centre, where the interpolated excess stays
        // below the threshold.
        const double from_actor = std::abs(pixel->x() - 2 * std::round(pixel->x() / 2));
        const bool screen = from_actor >= (keyer.threshold() + 10) / 150.0;
        different += stats.outside[size_t(v) * config.offset_count + i] != (screen ? 1 : 0);
      }
    }
    ASSERT_GT(compared, 10000) << inward;
    // Only a projection within a few thousandths of a pixel of a column's border may differ.
    EXPECT_LE(different, compared / 500)
        << different << " of " << compared << ", inward " << inward;
  }
}

// Window points: a vertex's two neighbours lie window_m along the tangent nearest the vertical
// (unit, on the tangent plane); the statistics hold the vertices first, sampled exactly as without
// a window, then each side's points.
TEST_F(EllipsoidScene, WindowPointsAreSampledAfterTheVertices) {
  const Eigen::Vector3f level(0.6f, 0.8f, 0.0f), tilted = Eigen::Vector3f(1, 0, 2).normalized();
  EXPECT_TRUE(windowDirection(level).cwiseAbs().isApprox(Eigen::Vector3f::UnitZ()));
  for (const Eigen::Vector3f& n : {level, tilted, Eigen::Vector3f(0, 0, 1)}) {
    const Eigen::Vector3f d = windowDirection(n);
    EXPECT_NEAR(d.norm(), 1.0f, 1e-6f);
    EXPECT_NEAR(d.dot(n), 0.0f, 1e-6f);
  }
  EXPECT_GT(std::abs(windowDirection(tilted).z()), 0.4f);  // toward the vertical

  const TriangleMesh sphere = testing::icosphere(shape_.centre, 0.27, 2);
  std::vector<int> all;
  for (int c = 0; c < rig_->cameraCount(); ++c) all.push_back(c);
  RefineConfig single_point;
  single_point.window_points = 1;
  RefinementStatistics alone, window;
  RefinementSampler(single_point)
      .sample(cameras(all), sphere.positions, sphere.normals, sphere.triangles, alone);
  RefinementSampler(RefineConfig{})
      .sample(cameras(all), sphere.positions, sphere.normals, sphere.triangles, window);
  const int n = sphere.vertexCount(), m = RefineConfig{}.offset_count;
  ASSERT_EQ(alone.vertex_count, n);
  ASSERT_EQ(window.vertex_count, 3 * n);
  const size_t samples = size_t(n) * m;
  EXPECT_TRUE(std::equal(alone.outside.begin(), alone.outside.end(), window.outside.begin()));
  EXPECT_TRUE(std::equal(alone.squares.begin(), alone.squares.end(), window.squares.begin()));
  EXPECT_TRUE(std::equal(alone.sums.begin(), alone.sums.end(), window.sums.begin()));
  // The sides' points see other pixels: their colours differ from the vertices'.
  EXPECT_FALSE(std::equal(alone.sums.begin(), alone.sums.end(), window.sums.begin() + 3 * samples));
  EXPECT_FALSE(std::equal(alone.sums.begin(), alone.sums.end(), window.sums.begin() + 6 * samples));
}

// A camera knocked toward the wall sees only the screen: every sample would lie outside its
// silhouette, which drops every sample's colours and leaves the mesh to the hull term alone. It is
// left out, and the statistics are those of the other cameras; a camera that sees the shape is not.
// A vertex is on a camera's contour where the camera sees it edge-on with nothing of the mesh
// behind it: a sphere with a second one behind it, half a radius aside, has a contour on the side
// away from the second sphere only (there the hull's crossing is the surface; on the other side
// the camera's silhouette is the sphere behind).
TEST_F(EllipsoidScene, MarksTheVerticesOnACamerasContour) {
  const Camera& camera = rig_->camera(0);
  const Eigen::Vector3d centre = camera.centre();
  const Eigen::Vector3d ahead = (shape_.centre - centre).normalized();
  const Eigen::Vector3d side = camera.rotation().row(0).transpose();  // the image's x, in the world
  const TriangleMesh front = testing::icosphere(shape_.centre, 0.25, 3);
  const TriangleMesh behind =
      testing::icosphere(shape_.centre + 0.6 * ahead + 0.25 * side, 0.25, 3);
  const int n = front.vertexCount();
  const TriangleMesh both = joined(front, behind);
  RefineConfig config;
  config.depth_map_step = 4;
  config.contour_probe_m = 0.04;  // beyond a depth map's cell at 2 m on these small cameras
  RefinementSampler sampler(config);
  RefinementStatistics stats;
  sampler.sample(cameras({0}), both.positions, both.normals, both.triangles, stats);
  ASSERT_EQ(sampler.seesNobody()[0], 0);
  int away = 0, away_marked = 0, toward_marked = 0, facing_marked = 0;
  for (int v = 0; v < n; ++v) {
    const Eigen::Vector3d normal = front.normals.col(v).cast<double>();
    const Eigen::Vector3d to_camera = (centre - front.positions.col(v).cast<double>()).normalized();
    const double facing = normal.dot(to_camera), aside = normal.dot(side);
    const bool marked = stats.contour[v] != 0;
    if (facing > 0.35) facing_marked += marked;
    if (facing > 0.05 && facing <= 0.25 && aside < -0.9) ++away, away_marked += marked;
    if (aside > 0.9) toward_marked += marked;
  }
  EXPECT_EQ(facing_marked, 0);
  EXPECT_EQ(toward_marked, 0);
  ASSERT_GE(away, 3);
  EXPECT_EQ(away_marked, away);
  // Only the mesh's vertices: the window points come after them and are never marked.
  EXPECT_EQ(std::count(stats.contour.begin() + 2 * n, stats.contour.end(), 1), 0);
  const auto marked = [&] { return std::count(stats.contour.begin(), stats.contour.end(), 1); };
  const long with_term = marked();
  // The contour term off: the outward term's split still needs the marks.
  config.contour_weight = 0;
  RefinementSampler split(config);
  split.sample(cameras({0}), both.positions, both.normals, both.triangles, stats);
  EXPECT_EQ(marked(), with_term);
  // Neither: nothing is marked.
  config.off_contour_outward_weight = config.outward_weight;
  RefinementSampler off(config);
  off.sample(cameras({0}), both.positions, both.normals, both.triangles, stats);
  EXPECT_EQ(marked(), 0);
}

TEST_F(EllipsoidScene, ACameraThatSeesNobodyIsLeftOut) {
  const TriangleMesh sphere = testing::icosphere(shape_.centre, 0.27, 2);
  std::vector<int> all, others;
  for (int c = 0; c < rig_->cameraCount(); ++c) {
    all.push_back(c);
    if (c != 2) others.push_back(c);
  }
  Image screen = (*images_)[2];
  for (size_t p = 0; p + 2 < screen.pixels.size(); p += 3) {
    screen.pixels[p] = 40, screen.pixels[p + 1] = 150, screen.pixels[p + 2] = 60;
  }
  std::vector<SamplerCamera> inputs = cameras(all);
  inputs[2].image = screen.view();
  RefinementSampler sampler{RefineConfig{}};
  RefinementStatistics with_screen, without;
  sampler.sample(cameras(all), sphere.positions, sphere.normals, sphere.triangles, with_screen);
  EXPECT_EQ(std::count(sampler.seesNobody().begin(), sampler.seesNobody().end(), 1), 0);
  sampler.sample(inputs, sphere.positions, sphere.normals, sphere.triangles, with_screen);
  ASSERT_EQ(sampler.seesNobody().size(), all.size());
  for (int c : all) EXPECT_EQ(sampler.seesNobody()[c], c == 2) << "camera " << c;
  sampler.sample(cameras(others), sphere.positions, sphere.normals, sphere.triangles, without);
  EXPECT_TRUE(with_screen == without);
}

TEST_F(EllipsoidScene, DistributedCombinationEqualsOneProcess) {
  const TriangleMesh sphere = testing::icosphere(shape_.centre, 0.27, 2);
  RefineConfig config;
  config.t_max_m = 0.08;
  RefinementSampler sampler(config);
  std::vector<int> all;
  for (int c = 0; c < rig_->cameraCount(); ++c) all.push_back(c);
  RefinementStatistics single;
  sampler.sample(cameras(all), sphere.positions, sphere.normals, sphere.triangles, single);

  // Each node samples its own cameras and sends the compressed wire form; the module combines,
  // in any order.
  std::vector<std::vector<uint8_t>> wire(rig_->nodeCount());
  RefinementStatistics part;
  RefinementStatisticsCodec node_codec, module_codec;
  for (int n = 0; n < rig_->nodeCount(); ++n) {
    sampler.sample(cameras(rig_->nodes()[n].cameras), sphere.positions, sphere.normals,
                   sphere.triangles, part);
    node_codec.encode(part, wire[n]);
    ASSERT_TRUE(isCompressedRefinementStatistics(wire[n]));
  }
  for (const std::vector<int>& order : {std::vector<int>{0, 1, 2, 3}, {3, 1, 0, 2}}) {
    RefinementStatistics combined, decoded;
    combined.reset(single.vertex_count, config.offset_count, config.colour_bits);
    for (int n : order) {
      const Status decoded_status = decodeRefinementStatistics(wire[n], decoded);
      ASSERT_TRUE(decoded_status.ok()) << decoded_status.error();
      ASSERT_TRUE(combined.add(decoded));
    }
    EXPECT_TRUE(combined == single);
    // The module's fast path, straight from the wire.
    RefinementStatistics fast;
    fast.reset(single.vertex_count, config.offset_count, config.colour_bits);
    for (int n : order) ASSERT_TRUE(module_codec.add(wire[n], fast).ok());
    fast.dropOutside();
    EXPECT_TRUE(fast == single);
    MeshRefiner a(config, sphere.vertexCount(), sphere.triangles),
        b(config, sphere.vertexCount(), sphere.triangles);
    std::vector<uint8_t> oa, ob;
    ASSERT_TRUE(a.refine(single, oa));
    ASSERT_TRUE(b.refine(combined, ob));
    EXPECT_EQ(oa, ob);
  }
}

}  // namespace
}  // namespace lumistage
