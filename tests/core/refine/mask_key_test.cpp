// Keying from another tool's masks (MaskKey): the sampler finds the mask's edge below a pixel.
#include <gtest/gtest.h>

#include <cmath>

#include "core/imaging/keyer.h"
#include "core/refine/refinement_sampler.h"
#include "tests/core/refine/refine_test_scene.h"

namespace lumistage {
namespace {

TEST(MaskKey, LevelsAreTheActorsInsideTheMaskAndTheBackgroundsOutside) {
  // 4x4, the actor in the left column and in the top-left 2x2 cell's right column too.
  const uint8_t mask[16] = {255, 255, 0, 0,  //
                            255, 255, 0, 0,  //
                            255, 0,   0, 0,  //
                            255, 0,   0, 0};
  const MaskKey key(mask, 4, 4);
  EXPECT_EQ(key.level(0, 0), -1.0f);
  EXPECT_EQ(key.level(2, 0), 1.0f);
  EXPECT_EQ(key.level(-1, 0), 1.0f);                    // beyond the mask: background
  EXPECT_TRUE(key.isForeground(Rgb{0, 255, 0}, 1, 1));  // whatever the colour
  EXPECT_FALSE(key.isForeground(Rgb{200, 30, 30}, 1, 2));
  // Pure: the background's share under purity / 2.
  EXPECT_TRUE(key.isPureForegroundLevel(-0.8f, 0, 0, 0.4f));
  EXPECT_FALSE(key.isPureForegroundLevel(-0.5f, 0, 0, 0.4f));
  EXPECT_EQ(key.isPureForegroundLevel(-0.1f, 0, 0, 1.0f), key.isForegroundLevel(-0.1f, 0, 0));
  // On Bayer, a pixel's level is its 2x2 cell's mean, as its colour is the cell's.
  const MaskKey cells(mask, 4, 4, true);
  EXPECT_EQ(cells.level(1, 1), -1.0f);
  EXPECT_EQ(cells.level(0, 3), 0.0f);  // half the cell
  EXPECT_EQ(cells.level(3, 3), 1.0f);
}

// Every camera's mask of the ellipsoid: the pixels whose centre's ray meets it. Its edge lies
// within half a pixel of the true silhouette's.
std::vector<std::vector<uint8_t>> ellipsoidMasks(const Rig& rig, const testing::Ellipsoid& shape) {
  std::vector<std::vector<uint8_t>> masks(rig.cameraCount());
  for (int c = 0; c < rig.cameraCount(); ++c) {
    const Camera& camera = rig.camera(c);
    masks[c].assign(size_t(camera.width()) * camera.height(), 0);
    for (int y = 0; y < camera.height(); ++y) {
      for (int x = 0; x < camera.width(); ++x) {
        const std::optional<Ray> ray = camera.unproject(Eigen::Vector2d(x, y));
        if (ray && shape.hit(ray->origin, ray->direction) > 0)
          masks[c][size_t(y) * camera.width() + x] = 255;
      }
    }
  }
  return masks;
}

// Images with no green screen (grey everywhere, the ellipsoid too: nothing a colour key could
// key) and the ellipsoid's masks: the sampler keys from the masks and locates each silhouette's
// edge, where the samples leave it, to a fraction of a pixel of the true hull's, far nearer than
// halfway between the samples.
TEST(RefinementSampler, KeyedFromMasksLocatesTheMasksEdgeBelowAPixel) {
  const testing::Ellipsoid shape;
  const Rig rig = testing::smallRing();
  const std::vector<std::vector<uint8_t>> masks = ellipsoidMasks(rig, shape);
  std::vector<Image> images(rig.cameraCount());
  std::vector<MaskKey> keys;
  std::vector<SamplerCamera> cameras;
  for (int c = 0; c < rig.cameraCount(); ++c) {
    const Camera& camera = rig.camera(c);
    images[c].resize(PixelFormat::kRgb8, camera.width(), camera.height());
    std::fill(images[c].pixels.begin(), images[c].pixels.end(), uint8_t(128));
    keys.emplace_back(masks[c].data(), camera.width(), camera.height());
  }
  for (int c = 0; c < rig.cameraCount(); ++c)
    cameras.push_back({&rig.camera(c), images[c].view(), nullptr, nullptr, &keys[c]});
  const TriangleMesh sphere = testing::icosphere(shape.centre, 0.28, 2);  // 162 vertices
  RefineConfig config;
  config.t_max_m = 0.09;
  config.offset_count = 7;  // 21 mm apart (2.9 pixels at the ellipsoid): halfway is far off
  config.depth_map_step = 4;
  config.window_points = 1;
  RefinementSampler sampler(config);
  RefinementStatistics stats;
  sampler.sample(cameras, sphere.positions, sphere.normals, sphere.triangles, stats);
  for (uint8_t nobody : sampler.seesNobody()) EXPECT_EQ(nobody, 0);
  // A pixel's width at the ellipsoid's centre, from the nearest camera.
  const Camera& first = rig.camera(0);
  const double pixel = (first.centre() - shape.centre).norm() / first.intrinsics().fy;
  const testing::EdgeDistances e = testing::hullEdgeDistances(rig, shape, sphere, config, stats);
  const double step = config.offsetAt(1) - config.offsetAt(0);
  const int edges = e.edges, leaving = e.leaving;
  const double located = e.located, halfway = e.halfway;
  ASSERT_GT(edges, 100) << leaving << " samples where the hull leaves";
  EXPECT_GT(edges, leaving * 9 / 10);
  // A step is 2.9 pixels at the ellipsoid: halfway misses by a quarter step on average (0.77 pixels
  // when written), the located edges by 0.19 pixels, within a mask's own uncertainty (its pixels
  // are whole: half a pixel at most).
  EXPECT_GT(halfway, 0.5 * pixel) << "step " << step / pixel << " pixels";
  EXPECT_LT(located, 0.3 * pixel) << "located " << located / pixel << " pixels, halfway "
                                  << halfway / pixel << " pixels";
  EXPECT_LT(located, 0.4 * halfway);
}

}  // namespace
}  // namespace lumistage
