// The virtual studio's renderer on a real headless OpenGL context (Mesa llvmpipe on a machine
// without GPU), checked against the camera model on the CPU.
#include "core/sim/studio_renderer.h"

#include <gtest/gtest.h>

#include <numbers>

#include "core/body/human_model.h"
#include "core/geometry/ring_rig.h"
#include "core/render/egl_context.h"

namespace lumistage {
namespace {

// The silhouette the camera model predicts: every triangle projected with exact lens distortion
// (Camera::project) and filled at pixel centres, as a rasteriser samples them.
std::vector<uint8_t> projectedSilhouette(const Camera& camera, const Eigen::Matrix3Xf& positions,
                                         const std::vector<Eigen::Vector3i>& triangles) {
  std::vector<uint8_t> mask(size_t(camera.width()) * camera.height(), 0);
  std::vector<Eigen::Vector2d> pixel(positions.cols());
  for (int v = 0; v < positions.cols(); ++v)
    pixel[v] = *camera.project(positions.col(v).cast<double>());
  for (const Eigen::Vector3i& t : triangles) {
    const Eigen::Vector2d a = pixel[t[0]], b = pixel[t[1]], c = pixel[t[2]];
    const double area = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    if (area == 0) continue;
    const int x0 = std::max(0, int(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(camera.width() - 1, int(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, int(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(camera.height() - 1, int(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const Eigen::Vector2d p(x, y);
        auto edge = [&](const Eigen::Vector2d& u, const Eigen::Vector2d& w) {
          return ((w - u).x() * (p - u).y() - (w - u).y() * (p - u).x()) / area;
        };
        if (edge(a, b) >= 0 && edge(b, c) >= 0 && edge(c, a) >= 0)
          mask[size_t(y) * camera.width() + x] = 255;
      }
    }
  }
  return mask;
}

// The virtual studio's actor (clothed), of about `vertices` vertices.
SkinnedMesh clothedActor(int vertices, double height_m = HumanModelSpec{}.shape.height_m) {
  HumanModelSpec spec;
  spec.clothing = true;
  spec.target_vertices = vertices;
  spec.shape.height_m = height_m;
  return makeHumanModel(spec);
}

TEST(StudioRenderer, SilhouetteMatchesTheProjectedSurface) {
  EglContext gl;
  const SkinnedMesh actor = clothedActor(4000, 1.82);
  // A pose with bent limbs, turned and off-centre.
  Pose pose = Pose::rest(actor.skeleton.jointCount());
  pose.angles_rad[0] = Eigen::Vector3d(0, 0, 0.6);
  pose.root_translation_m = Eigen::Vector3d(0.3, -0.2, 0);
  pose.angles_rad[kRightShoulder] = Eigen::Vector3d(0, 1.1, 0.3);
  pose.angles_rad[kRightElbow] = Eigen::Vector3d(0, 0, 1.2);
  pose.angles_rad[kLeftHip] = Eigen::Vector3d(0.6, 0, 0);
  pose.angles_rad[kLeftKnee] = Eigen::Vector3d(-0.9, 0, 0);
  std::vector<Eigen::Affine3f> transforms;
  actor.skeleton.skinningTransforms(pose, transforms);
  Eigen::Matrix3Xf positions, normals;
  skinMesh(actor, transforms, positions, normals);

  StudioRenderer renderer(actor);
  renderer.setSurface(positions, normals);
  const Rig rig = makeRingRig({});
  std::vector<uint8_t> rgba;
  for (int c : {0, 3, 7}) {
    const Camera& camera = rig.camera(c);
    renderer.render(camera, StudioLook{}, 7u + c, rgba);
    ASSERT_EQ(rgba.size(), size_t(camera.width()) * camera.height() * 4);
    const std::vector<uint8_t> expected =
        projectedSilhouette(camera, positions, actor.rest.triangles);
    size_t both = 0, either = 0, actor_pixels = 0, green_background = 0, background = 0;
    for (size_t p = 0; p < expected.size(); ++p) {
      const bool rendered = rgba[4 * p + 3] > 127, predicted = expected[p] > 0;
      both += rendered && predicted;
      either += rendered || predicted;
      actor_pixels += rendered;
      if (!rendered) {
        ++background;
        const int r = rgba[4 * p], g = rgba[4 * p + 1], b = rgba[4 * p + 2];
        green_background += g > r + 40 && g > b + 40;
      }
    }
    const double iou = double(both) / double(either);
    EXPECT_GT(iou, 0.99) << camera.name();
    EXPECT_GT(actor_pixels, 15000u) << camera.name();  // the actor fills a good part of the view
    EXPECT_GT(double(green_background) / double(background), 0.99) << camera.name();
  }
}

TEST(StudioRenderer, ActorIsTexturedAndNoiseChangesWithTheSeed) {
  EglContext gl;
  const SkinnedMesh actor = clothedActor(3000);
  StudioRenderer renderer(actor);
  const Rig rig = makeRingRig({});
  std::vector<uint8_t> a, b;
  renderer.render(rig.camera(0), StudioLook{}, 1, a);
  renderer.render(rig.camera(0), StudioLook{}, 2, b);
  // Texture: the actor's colours vary a lot (stripes, denim, skin), not one flat colour.
  double sum = 0, sum2 = 0;
  size_t n = 0, differing = 0;
  for (size_t p = 0; p < a.size() / 4; ++p) {
    differing += a[4 * p + 1] != b[4 * p + 1];
    if (a[4 * p + 3] < 128) continue;
    const double luminance = 0.3 * a[4 * p] + 0.6 * a[4 * p + 1] + 0.1 * a[4 * p + 2];
    sum += luminance;
    sum2 += luminance * luminance;
    ++n;
  }
  ASSERT_GT(n, 1000u);
  const double stddev = std::sqrt(sum2 / n - (sum / n) * (sum / n));
  EXPECT_GT(stddev, 25.0);
  // Sensor noise: another seed changes most pixels by a level or two.
  EXPECT_GT(differing, a.size() / 4 / 2);
}

// A camera's pixel integrates the light over its area: the actor's pattern in a pixel must be the
// mean of the same view rendered 4x4 finer, not a point sample of it (stair-stepped stripe edges
// that no other view of the surface could reproduce). Compared over the actor's inside, where all
// 16 fine samples are the actor, without noise. Point-sampled stripes score 30.7 dB here; the
// pattern filtered over each pixel's footprint 35.2 dB (what is left: the 5 mm grain, point
// sampled).
TEST(StudioRenderer, PatternIsIntegratedOverEachPixel) {
  EglContext gl;
  const SkinnedMesh actor = clothedActor(3000);
  StudioRenderer renderer(actor);
  const Rig rig = makeRingRig({});
  StudioLook look;
  look.noise_sigma = 0;
  look.spill = 0;  // view-dependent, and it varies across a fine pixel's footprint
  const int s = 4;
  for (int c : {0, 5}) {
    const Camera& camera = rig.camera(c);
    Intrinsics k = camera.intrinsics();
    // Pixel centres at integers: fine pixel u' = s (u + 0.5) - 0.5.
    k.fx *= s;
    k.fy *= s;
    k.skew *= s;
    k.cx = s * (k.cx + 0.5) - 0.5;
    k.cy = s * (k.cy + 0.5) - 0.5;
    const Camera fine_camera("fine", s * camera.width(), s * camera.height(), k,
                             camera.distortion(), camera.rotation(), camera.translation());
    std::vector<uint8_t> image, fine;
    renderer.render(camera, look, 1, image);
    renderer.render(fine_camera, look, 1, fine);
    double squared = 0;
    size_t pixels = 0;
    for (int y = 0; y < camera.height(); ++y) {
      for (int x = 0; x < camera.width(); ++x) {
        int mean[3] = {0, 0, 0};
        bool inside = true;
        for (int j = 0; j < s * s && inside; ++j) {
          const size_t q = (size_t(s * y + j / s) * fine_camera.width() + s * x + j % s) * 4;
          inside = fine[q + 3] > 127;
          for (int ch = 0; ch < 3; ++ch) mean[ch] += fine[q + ch];
        }
        if (!inside) continue;
        const size_t p = (size_t(y) * camera.width() + x) * 4;
        for (int ch = 0; ch < 3; ++ch) {
          const double d = image[p + ch] - mean[ch] / double(s * s);
          squared += d * d;
        }
        ++pixels;
      }
    }
    ASSERT_GT(pixels, 10000u) << camera.name();
    const double psnr = 10 * std::log10(255.0 * 255.0 * 3 * pixels / squared);
    EXPECT_GT(psnr, 33.0) << camera.name();
  }
}

}  // namespace
}  // namespace lumistage
