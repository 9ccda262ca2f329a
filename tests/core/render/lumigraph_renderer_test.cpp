// Unstructured lumigraph rendering on a real headless OpenGL context (Mesa llvmpipe on a machine
// without GPU), against the virtual studio's ground truth.
#include "core/render/lumigraph_renderer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <memory>

#include "core/base/error.h"
#include "core/capture/image.h"
#include "core/eval/view_metrics.h"
#include "core/imaging/partial_image_codec.h"
#include "core/render/egl_context.h"
#include "core/render/partial_image_blender.h"
#include "core/render/silhouette_feather.h"
#include "core/sim/virtual_studio.h"
#include "tests/core/refine/refine_test_scene.h"
#include "tests/core/render/lumigraph_test_studio.h"
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;
using testing::covered;
using testing::LumigraphRendererTest;

TEST_F(LumigraphRendererTest, DesiredCameraOnAnInputCameraGivesThatCamerasImage) {
  auto renderer = makeRenderer();
  std::vector<uint8_t> rendered;
  for (int c : {0, 5, 9}) {
    const Camera& camera = rig().camera(c);
    renderer->render(camera, rendered);
    const ViewScore score = compareOverMask(rendered, frame_->images[c], frame_->masks[c],
                                            camera.width(), camera.height());
    EXPECT_GT(score.pixels, 10000) << camera.name();
    EXPECT_GT(score.psnr_db, 38.0) << camera.name();
    EXPECT_GT(score.ssim, 0.97) << camera.name();
  }
}

TEST_F(LumigraphRendererTest, NodeWeightsSumToOneAndVanishForCamerasThatDoNotContribute) {
  const Camera desired = desiredView();
  // The geometric weights alone (no misregistration's factor, which divides each camera's weight
  // by what its image shows) are shares of the rig's total: the nodes' sum to one.
  LumigraphParams geometric;
  geometric.misregistration_m = 0;
  std::vector<std::vector<uint8_t>> partials, divided;
  for (const RigNode& node : rig().nodes()) {
    partials.emplace_back();
    makeRenderer(node.cameras, geometric)->render(desired, partials.back());
    divided.emplace_back();
    makeRenderer(node.cameras)->render(desired, divided.back());
  }
  std::vector<uint8_t> local;
  makeRenderer({}, geometric)->render(desired, local);
  ASSERT_GT(covered(local), 5000);
  int64_t off = 0, inside = 0, rounded_down = 0, more = 0, less = 0;
  for (size_t i = 0; i < local.size() / 4; ++i) {
    double sum = 0, sum_divided = 0;
    for (const auto& p : partials) sum += shareOfAlpha(p[4 * i + 3]);
    for (const auto& p : divided) sum_divided += shareOfAlpha(p[4 * i + 3]);
    if (local[4 * i + 3] == 0) {
      EXPECT_EQ(sum, 0) << "pixel " << i;  // no surface, or no camera sees it: no weight
      EXPECT_EQ(sum_divided, 0) << "pixel " << i;
      continue;
    }
    // Own share / total of the same interpolated weights: 1, but where the total falls toward 0
    // (a vertex no camera sees, on the rim) their float ratio may round one step down.
    EXPECT_GE(local[4 * i + 3], 254) << "pixel " << i;
    rounded_down += local[4 * i + 3] != 255;
    ++inside;
    off += std::abs(sum - 1) > 0.03;  // shares each rounded to 2.2%
    // Divided, a camera weighs less: the shares' sum falls where the images show edges.
    more += sum_divided > sum * 1.03 + 1e-6;
    less += sum_divided < 0.5 * sum;
  }
  EXPECT_EQ(off, 0) << "of " << inside;
  EXPECT_LT(rounded_down * 1000, inside);
  EXPECT_EQ(more, 0) << "of " << inside;
  EXPECT_GT(less * 20, inside) << "of " << inside;  // the shirt's stripes, the band, the hair
  EXPECT_LT(less * 2, inside) << "of " << inside;   // not the flat skin and cloth
  // Where the images are flat, every camera keeps its whole weight.
  const Camera& any = rig().camera(0);
  const std::vector<uint8_t> flat(size_t(any.width()) * any.height() * 4, 128);
  std::vector<std::vector<uint8_t>> flat_partials;
  for (const RigNode& node : rig().nodes()) {
    LumigraphRenderer renderer(rig(), node.cameras);
    renderer.setMesh(frame_->surface.positions, frame_->surface.normals, frame_->surface.triangles);
    for (size_t j = 0; j < node.cameras.size(); ++j)
      renderer.setImageRgba(int(j), flat.data(), any.width(), any.height());
    flat_partials.emplace_back();
    renderer.render(desired, flat_partials.back());
  }
  int64_t flat_off = 0;
  for (size_t i = 0; i < local.size() / 4; ++i) {
    if (local[4 * i + 3] == 0) continue;
    double sum = 0;
    for (const auto& p : flat_partials) sum += shareOfAlpha(p[4 * i + 3]);
    flat_off += std::abs(sum - 1) > 0.03;
  }
  EXPECT_EQ(flat_off, 0) << "of " << inside;
  // Cameras 6 and 7 face the desired view from the other side of the stage: with three cameras
  // blended, never among the nearest in angle, their weight is zero everywhere. (With four, a
  // point on the rim that only five cameras face may take one of them: 2 pixels of this view.)
  LumigraphParams three;
  three.k = 3;
  std::vector<uint8_t> behind;
  makeRenderer({6, 7}, three)->render(desired, behind);
  EXPECT_EQ(covered(behind), 0);
}

// A camera's weight is divided by the error its image would bring were the surface a few
// millimetres off along the desired ray: a desired camera above camera 0 moves camera 0's texels
// vertically for such an error, so an image of horizontal stripes gives its weight away on their
// edges, one of vertical stripes (the same image turned) keeps it.
TEST_F(LumigraphRendererTest, ACameraGivesWayWhereItsImageWouldMisregister) {
  const Camera& input = rig().camera(0);
  const Camera desired = lookingAtTheActor(input.centre() + Eigen::Vector3d(0, 0, 1.2));
  const int w = input.width(), h = input.height();
  const auto shareBelowHalf = [&](bool horizontal) {
    std::vector<uint8_t> stripes(size_t(w) * h * 4, 255);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        if (((horizontal ? y : x) / 4) % 2) std::fill_n(&stripes[(size_t(y) * w + x) * 4], 3, 0);
    const auto render = [&](const LumigraphParams& params) {
      LumigraphRenderer renderer(rig(), {0}, params);
      renderer.setMesh(frame_->surface.positions, frame_->surface.normals,
                       frame_->surface.triangles);
      renderer.setImageRgba(0, stripes.data(), w, h);
      std::vector<uint8_t> partial;
      renderer.render(desired, partial);
      return partial;
    };
    // Against the same camera's share with the misregistration off.
    LumigraphParams geometric;
    geometric.misregistration_m = 0;
    const std::vector<uint8_t> partial = render({}), undivided = render(geometric);
    int64_t drawn = 0, halved = 0;
    for (size_t i = 3; i < partial.size(); i += 4) {
      if (undivided[i] == 0) continue;
      ++drawn;
      halved += shareOfAlpha(partial[i]) < 0.5 * shareOfAlpha(undivided[i]);
    }
    EXPECT_GT(drawn, 3000);
    return double(halved) / double(std::max<int64_t>(drawn, 1));
  };
  const double across = shareBelowHalf(true), along = shareBelowHalf(false);
  EXPECT_GT(across, 0.2);  // 0.42 here: the texels within the shift of an edge
  EXPECT_LT(along, 0.02);  // 0 here
}

TEST_F(LumigraphRendererTest, DistributedImageEqualsTheSingleProcessImage) {
  const Camera desired = desiredView();
  PartialImageBlender blender;
  blender.reset(desired.width(), desired.height());
  std::vector<uint8_t> partial, encoded, decoded;
  for (const RigNode& node : rig().nodes()) {
    makeRenderer(node.cameras)->render(desired, partial);
    encodeAlphaRuns(partial, encoded);  // through the wire encoding
    ASSERT_TRUE(decodeAlphaRuns(encoded, partial.size() / 4, decoded));
    ASSERT_TRUE(blender.add(decoded));
  }
  std::vector<uint8_t> distributed, local, local_blended;
  blender.finish(distributed);
  makeRenderer()->render(desired, local);
  PartialImageBlender single;
  single.reset(desired.width(), desired.height());
  single.add(local);
  single.finish(local_blended);
  // What eval and `lumistage render` make of the single-process image: the same.
  finishSingleProcessView(local, desired.width(), desired.height());
  EXPECT_EQ(local, local_blended);
  ASSERT_EQ(distributed.size(), local_blended.size());
  double sum = 0;
  int worst = 0;
  for (size_t i = 0; i < local_blended.size(); ++i) {
    const int d = std::abs(int(distributed[i]) - int(local_blended[i]));
    sum += d;
    worst = std::max(worst, d);
  }
  EXPECT_LT(sum / local_blended.size(), 0.1);
  EXPECT_LE(worst, 3);  // 8-bit colours and alpha shares, rounded on each node
  EXPECT_EQ(covered(distributed), covered(local_blended));
}

// The visibility masks the studio computes and sends give the nodes the image their own would;
// the masks matter (all cameras seeing every vertex gives another image).
TEST_F(LumigraphRendererTest, GivenVisibilityGivesTheImageOfTheRenderersOwn) {
  auto renderer = makeRenderer();
  const TriangleMesh& surface = frame_->surface;
  std::vector<uint8_t> own, given, unoccluded;
  renderer->render(desiredView(), own);
  VertexVisibility visibility;
  visibility.compute(rig(), surface.positions, surface.triangles,
                     renderer->params().depth_map_divisor, renderer->params().depth_tolerance_m);
  renderer->setMesh(surface.positions, surface.normals, surface.triangles, visibility.masks());
  renderer->render(desiredView(), given);
  ASSERT_GT(covered(own), 5000);
  EXPECT_EQ(given, own);
  const std::vector<CameraMask> all(visibility.masks().size(), 0xffffffff);
  renderer->setMesh(surface.positions, surface.normals, surface.triangles, all);
  renderer->render(desiredView(), unoccluded);
  const Camera view = desiredView();
  const std::vector<uint8_t> all_pixels(size_t(view.width()) * view.height(), 1);
  const ViewScore score = compareOverMask(unoccluded, own, all_pixels, view.width(), view.height());
  std::printf("  no occlusion against the visibility masks: %.1f dB\n", score.psnr_db);
  EXPECT_LT(score.psnr_db, 50.0);
  const std::vector<CameraMask> short_masks(10, 0xffffffff);
  EXPECT_THROW(
      renderer->setMesh(surface.positions, surface.normals, surface.triangles, short_masks), Error);
}

// A camera's foreground mask scales its weight where it samples: cameras that see the actor there
// colour the pixel; where every camera's mask says "background" within a cell of the actor, the
// unmasked colour is kept at a sixteenth of the weight (drawn, but outweighed by any node whose
// cameras see the actor); further off in every camera, nothing is drawn.
TEST_F(LumigraphRendererTest, ForegroundMasksTakeAwayWhatIsOffTheActor) {
  auto renderer = makeRenderer();
  std::vector<uint8_t> before, after;
  renderer->render(desiredView(), before);
  ASSERT_GT(covered(before), 5000);
  const int w = rig().camera(0).width() / 8, h = rig().camera(0).height() / 8;
  std::vector<uint8_t> mask(size_t(w) * h, 255);
  auto maskAll = [&] {
    for (int c = 0; c < rig().cameraCount(); ++c) renderer->setMask(c, mask, w, h);
    renderer->render(desiredView(), after);
  };
  maskAll();
  EXPECT_EQ(after, before);  // all foreground: as without masks
  auto faint = [](const std::vector<uint8_t>& rgba) {
    int64_t n = 0;
    for (size_t i = 3; i < rgba.size(); i += 4) n += rgba[i] > 0 && rgba[i] < 20;
    return n;
  };
  // The left half of every camera's image is background: some pixels are off the actor in every
  // camera that colours them; beside the halves' edge they fall back to the unmasked colour, beyond
  // a cell from it they are not drawn.
  for (int y = 0; y < h; ++y) std::fill_n(&mask[size_t(y) * w], w / 2, uint8_t(0));
  maskAll();
  EXPECT_LT(covered(after), covered(before) - 300);
  EXPECT_GT(faint(after), 20);
  EXPECT_LT(faint(after), covered(after) / 4);
  // Background everywhere: nothing is drawn.
  std::fill(mask.begin(), mask.end(), uint8_t(0));
  maskAll();
  EXPECT_EQ(covered(after), 0);
  EXPECT_THROW(renderer->setMask(0, mask, w + 1, h), Error);
}

// A part of the mesh that every camera sees clearly off the actor (here a copy of the actor lifted
// 2.1 m, above the real one's head in every view, as a mis-posed limb or the generic mesh's foot
// beside the shoe is) is not drawn at all: with the cameras' silhouettes as masks, the view of the
// actor and the copy is the view of the actor alone, pixel for pixel. Without masks the copy shows.
// The same with masks of two sizes (cells of 4 pixels for some cameras, 8 for the others, as
// cameras of different sizes give): each is read where its own camera samples.
TEST_F(LumigraphRendererTest, WhatEveryCameraSeesClearlyOffTheActorIsNotDrawn) {
  const TriangleMesh& actor = frame_->surface;
  const int n = actor.vertexCount();
  Eigen::Matrix3Xf positions(3, 2 * n), normals(3, 2 * n);
  positions << actor.positions, actor.positions.colwise() + Eigen::Vector3f(0, 0, 2.1f);
  normals << actor.normals, actor.normals;
  std::vector<Eigen::Vector3i> triangles = actor.triangles;
  for (const Eigen::Vector3i& t : actor.triangles) triangles.push_back(t.array() + n);
  // Each camera's silhouette in cells of `cell` pixels, a cell foreground when any pixel is.
  const auto setMasks = [&](LumigraphRenderer& renderer, bool mixed) {
    for (int c = 0; c < rig().cameraCount(); ++c) {
      const int cell = mixed && c % 2 ? 8 : 4;
      const int w = rig().camera(c).width() / cell, h = rig().camera(c).height() / cell;
      std::vector<uint8_t> cells(size_t(w) * h, 0);
      for (int y = 0; y < cell * h; ++y)
        for (int x = 0; x < cell * w; ++x)
          if (frame_->masks[c][size_t(y) * rig().camera(c).width() + x])
            cells[size_t(y / cell) * w + x / cell] = 255;
      renderer.setMask(c, cells, w, h);
    }
  };
  std::vector<uint8_t> unmasked;
  {
    auto renderer = makeRenderer();
    renderer->setMesh(positions, normals, triangles);
    renderer->render(desiredView(), unmasked);
  }
  for (const bool mixed : {false, true}) {
    std::vector<uint8_t> alone, with_copy;
    auto renderer = makeRenderer();
    setMasks(*renderer, mixed);
    renderer->render(desiredView(), alone);
    renderer->setMesh(positions, normals, triangles);
    setMasks(*renderer, mixed);  // as every frame gives them
    renderer->render(desiredView(), with_copy);
    ASSERT_GT(covered(alone), 5000) << "mixed " << mixed;
    EXPECT_GT(covered(unmasked), covered(alone) + 1000) << "the copy is not in the view";
    EXPECT_EQ(with_copy, alone) << "mixed " << mixed;
  }
}

// A camera with no picture this frame (its node zeroes its mask; its texture keeps whatever it
// held): nothing of it reaches the view, not even in the rim's fallback colour. Its old picture
// magenta or black, the view is the same.
TEST_F(LumigraphRendererTest, ACameraWhoseMaskIsAllOffGivesNoColour) {
  std::vector<std::vector<uint8_t>> views;
  for (const std::array<uint8_t, 4> old :
       {std::array<uint8_t, 4>{255, 0, 255, 255}, std::array<uint8_t, 4>{0, 0, 0, 255}}) {
    auto renderer = makeRenderer({0, 1});
    const Camera& c0 = rig().camera(0);
    std::vector<uint8_t> picture(size_t(c0.width()) * c0.height() * 4);
    for (size_t i = 0; i < picture.size(); i += 4) std::copy(old.begin(), old.end(), &picture[i]);
    renderer->setImageRgba(0, picture.data(), c0.width(), c0.height());
    const int w = c0.width() / 4, h = c0.height() / 4;
    renderer->setMask(0, std::vector<uint8_t>(size_t(w) * h, 0), w, h);
    const Camera& c1 = rig().camera(1);
    std::vector<uint8_t> cells(size_t(w) * h, 0);
    for (int y = 0; y < 4 * h; ++y)
      for (int x = 0; x < 4 * w; ++x)
        if (frame_->masks[1][size_t(y) * c1.width() + x]) cells[size_t(y / 4) * w + x / 4] = 255;
    renderer->setMask(1, cells, w, h);
    views.emplace_back();
    renderer->render(desiredView(), views.back());
  }
  ASSERT_GT(covered(views[0]), 5000);
  EXPECT_EQ(views[0], views[1]);
}

// A view larger than the device can draw is refused in words, and the renderer draws the next
// view as before (a refused allocation left the old one attached, read back at the new size).
TEST_F(LumigraphRendererTest, AViewTooLargeForTheDeviceIsRefused) {
  auto renderer = makeRenderer();
  std::vector<uint8_t> before, after;
  renderer->render(desiredView(), before);
  const Camera huge("huge", 100000, 10, {400, 400, 49999.5, 4.5, 0}, {}, desiredView().rotation(),
                    desiredView().translation());
  const std::string message = testing::errorOf([&] { renderer->render(huge, after); });
  EXPECT_NE(message.find("a view of 100000x10 pixels: this OpenGL device draws 1 to"),
            std::string::npos)
      << message;
  renderer->render(desiredView(), after);
  EXPECT_EQ(after, before);
}

TEST_F(LumigraphRendererTest, SeveralViewsOfOneFrameDoNotDisturbEachOther) {
  auto renderer = makeRenderer(rig().nodes()[1].cameras);
  const Camera desired = desiredView();
  const Camera& preview = rig().camera(rig().nodes()[1].cameras[0]);
  std::vector<uint8_t> first, other, again;
  renderer->render(desired, first);
  renderer->render(preview, other);
  renderer->render(desired, again);
  EXPECT_GT(covered(first), 1000);
  EXPECT_GT(covered(other), 1000);
  EXPECT_EQ(first, again);
}

TEST_F(LumigraphRendererTest, ClonesAppearWherePlacedWithTheirOwnViewDependentWeights) {
  auto renderer = makeRenderer();
  const Camera& camera = rig().camera(2);
  std::vector<uint8_t> original, cloned;
  renderer->render(camera, original);
  // A clone 0.8 m to the side and turned by 30 degrees about the vertical through the origin,
  // seen by the camera carried along with it: the same picture as the actor from the camera.
  Eigen::Affine3f clone = Eigen::Affine3f::Identity();
  clone.translate(Eigen::Vector3f(0.8f, -0.3f, 0.0f));
  clone.rotate(Eigen::AngleAxisf(0.52f, Eigen::Vector3f::UnitZ()));
  const Eigen::Affine3d c = clone.cast<double>();
  const Eigen::Matrix3d R = camera.rotation() * c.linear().transpose();
  const Camera carried("carried", camera.width(), camera.height(), camera.intrinsics(),
                       camera.distortion(), R, camera.translation() - R * c.translation());
  const Eigen::Affine3f both[] = {clone};
  renderer->render(carried, both, cloned);
  const ViewScore same =
      compareOverMask(cloned, original, frame_->masks[2], camera.width(), camera.height());
  EXPECT_GT(same.psnr_db, 40.0);
  // From the camera itself the clone covers where its placed surface projects.
  renderer->render(camera, both, cloned);
  Eigen::Vector2d centroid(0, 0), expected(0, 0);
  int64_t n = 0;
  for (int y = 0; y < camera.height(); ++y)
    for (int x = 0; x < camera.width(); ++x)
      if (cloned[4 * (size_t(y) * camera.width() + x) + 3]) centroid += Eigen::Vector2d(x, y), ++n;
  ASSERT_GT(n, 1000);
  centroid /= double(n);
  const Eigen::Matrix3Xf& p = frame_->surface.positions;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int v = 0; v < p.cols(); ++v) mean += (clone * Eigen::Vector3f(p.col(v))).cast<double>();
  expected = *camera.project(mean / double(p.cols()));
  EXPECT_LT((centroid - expected).norm(), 25.0)
      << centroid.transpose() << " vs " << expected.transpose();
  // Several clones: each a draw, all of them visible.
  const Eigen::Affine3f two[] = {Eigen::Affine3f::Identity(), clone};
  renderer->render(camera, two, cloned);
  EXPECT_GT(covered(cloned), n + covered(original) / 2);
}

TEST_F(LumigraphRendererTest, LeaveOneOutOnTheTrueSurfaceReachesTheTarget) {
  auto renderer = makeRenderer();
  const std::vector<ViewScore> scores =
      leaveOneOut(*renderer, rig(), frame_->images, frame_->masks);
  ASSERT_EQ(scores.size(), 12u);
  double psnr = 0, ssim = 0;
  for (size_t c = 0; c < scores.size(); ++c) {
    std::printf("  LOO %s: PSNR %.2f dB, SSIM %.3f\n", rig().camera(int(c)).name().c_str(),
                scores[c].psnr_db, scores[c].ssim);
    EXPECT_GT(scores[c].psnr_db, 25.0) << rig().camera(int(c)).name();
    psnr += scores[c].psnr_db / 12;
    ssim += scores[c].ssim / 12;
  }
  EXPECT_GT(psnr, 28.0);
  EXPECT_GT(ssim, 0.8);
}

// The flat triangles of a coarse mesh cut inside a curved surface's silhouette; rim dilation, or
// the Phong subdivision, brings the rendered silhouette back out to it, without drawing much
// beyond it.
TEST_F(LumigraphRendererTest, RimDilationKeepsTheSilhouetteOfACoarseSphere) {
  const Eigen::Vector3d centre(0, 0, 1.0);
  const double radius = 0.3;
  const TriangleMesh sphere = testing::icosphere(centre, radius, 1);  // 42 vertices, 19 cm edges
  const Camera& camera = rig().camera(2);
  // The true sphere's silhouette, pixel by pixel.
  std::vector<uint8_t> mask(size_t(camera.width()) * camera.height(), 0);
  for (int y = 0; y < camera.height(); ++y) {
    for (int x = 0; x < camera.width(); ++x) {
      const std::optional<Ray> ray = camera.unproject(Eigen::Vector2d(x, y));
      if (!ray) continue;
      const Eigen::Vector3d to_centre = centre - ray->origin;
      const double along = to_centre.dot(ray->direction);
      mask[size_t(y) * camera.width() + x] =
          along > 0 && (to_centre - along * ray->direction).norm() < radius;
    }
  }
  const std::vector<uint8_t> grey(size_t(camera.width()) * camera.height() * 4, 128);
  auto silhouetteErrors = [&](float rim_dilation, bool phong) {
    LumigraphParams params;
    params.rim_dilation = rim_dilation;
    params.phong_subdivision = phong;
    std::vector<int> all;
    for (int c = 0; c < rig().cameraCount(); ++c) all.push_back(c);
    LumigraphRenderer renderer(rig(), all, params);
    renderer.setMesh(sphere.positions, sphere.normals, sphere.triangles);
    for (int c = 0; c < rig().cameraCount(); ++c)
      renderer.setImageRgba(c, grey.data(), camera.width(), camera.height());
    std::vector<uint8_t> rendered;
    renderer.render(camera, rendered);
    int64_t inside = 0, missed = 0, beyond = 0;
    for (size_t i = 0; i < mask.size(); ++i) {
      const bool drawn = rendered[4 * i + 3] > 0;
      inside += mask[i];
      missed += mask[i] && !drawn;
      beyond += !mask[i] && drawn;
    }
    return std::array<double, 2>{double(missed) / inside, double(beyond) / inside};
  };
  const auto [missed_flat, beyond_flat] = silhouetteErrors(0.0f, false);
  const auto [missed, beyond] = silhouetteErrors(LumigraphParams{}.rim_dilation, false);
  std::printf("  sphere silhouette: missed %.2f%% -> %.2f%%, beyond %.2f%% -> %.2f%%\n",
              100 * missed_flat, 100 * missed, 100 * beyond_flat, 100 * beyond);
  // Subdivided as the curved surface (the default), with the rim dilation of the finer edges.
  const auto [missed_phong, beyond_phong] = silhouetteErrors(LumigraphParams{}.rim_dilation, true);
  std::printf("  Phong-subdivided: missed %.2f%%, beyond %.2f%%\n", 100 * missed_phong,
              100 * beyond_phong);
  EXPECT_LT(missed_phong, missed_flat / 3);
  EXPECT_LT(beyond_phong, missed_flat / 2);
  EXPECT_GT(missed_flat, 0.02);  // the flat triangles fall short by several per cent
  EXPECT_LT(beyond_flat, 0.002);
  EXPECT_LT(missed, missed_flat / 3);
  EXPECT_LT(beyond, missed_flat / 2);
  EXPECT_LT(missed + beyond, missed_flat);
}

TEST(PartialImageBlender, NormalisesAlphasPerPixel) {
  PartialImageBlender blender;
  blender.reset(2, 1);
  // Shares of a half (16 steps an octave below 255) and of one: (100 / 2 + 200) / 1.5 = 167 and
  // 30 / 1.5 = 20.
  const std::vector<uint8_t> a = {100, 0, 0, 239, 0, 0, 0, 0}, b = {200, 30, 0, 255, 0, 0, 0, 0};
  EXPECT_DOUBLE_EQ(shareOfAlpha(239), 0.5);
  EXPECT_DOUBLE_EQ(shareOfAlpha(255), 1.0);
  EXPECT_DOUBLE_EQ(shareOfAlpha(0), 0.0);
  blender.add(a);
  blender.add(b);
  EXPECT_FALSE(blender.add(std::vector<uint8_t>(4, 1)));
  std::vector<uint8_t> out;
  blender.finish(out);
  // The empty pixel beside it is feathered: 4/255 of the colour, premultiplied.
  EXPECT_EQ(out, (std::vector<uint8_t>{167, 20, 0, 255, 3, 0, 0, 4}));
}

TEST(PartialImageBlender, BlendsFromTheWireAndForgetsTheLastFrame) {
  // Two partial images of 7x5 with drawn pixels scattered across rows (runs that cross a row's
  // end, lone pixels, a pixel with colour and no weight), added from their alpha runs and as
  // whole images: the same blend.
  const int w = 7, h = 5;
  std::vector<uint8_t> a(w * h * 4, 0), b(w * h * 4, 0);
  for (int i : {5, 6, 7, 8, 20, 34}) {
    a[4 * i] = uint8_t(10 * i), a[4 * i + 1] = 3, a[4 * i + 2] = uint8_t(i), a[4 * i + 3] = 100;
  }
  for (int i : {0, 8, 9, 21, 33}) {
    b[4 * i] = 200, b[4 * i + 1] = uint8_t(7 * i), b[4 * i + 3] = uint8_t(20 + i);
  }
  b[4 * 22] = 50;  // colour without weight: not drawn
  std::vector<uint8_t> encoded_a, encoded_b, whole, runs;
  encodeAlphaRuns(a, encoded_a);
  encodeAlphaRuns(b, encoded_b);
  PartialImageBlender blender;
  blender.reset(w, h);
  ASSERT_TRUE(blender.add(a));
  ASSERT_TRUE(blender.add(b));
  blender.finish(whole);
  blender.reset(w, h);
  ASSERT_TRUE(blender.addAlphaRuns(encoded_a));
  ASSERT_TRUE(blender.addAlphaRuns(encoded_b));
  EXPECT_EQ(blender.added(), 2);
  blender.finish(runs);
  EXPECT_EQ(runs, whole);
  EXPECT_EQ(whole[4 * 8 + 3], 255);
  EXPECT_LT(whole[4 * 22 + 3], 128);  // not drawn, only feathered beside pixel 21
  const double share_a = shareOfAlpha(100), share_b = shareOfAlpha(28);
  EXPECT_NEAR(whole[4 * 8], (10 * 8 * share_a + 200 * share_b) / (share_a + share_b), 0.51);

  // The next frame draws b alone: nothing of a is left, neither where b is empty nor where both
  // drew.
  blender.reset(w, h);
  ASSERT_TRUE(blender.addAlphaRuns(encoded_b));
  std::vector<uint8_t> next, b_alone;
  blender.finish(next);
  PartialImageBlender fresh;
  fresh.reset(w, h);
  fresh.add(b);
  fresh.finish(b_alone);
  EXPECT_EQ(next, b_alone);

  // Runs that are not an encoding of this size add nothing.
  blender.reset(w, h);
  EXPECT_FALSE(blender.addAlphaRuns(std::span(encoded_a).first(encoded_a.size() - 1)));
  std::vector<uint8_t> other_size;
  encodeAlphaRuns(std::vector<uint8_t>(4 * (w * h + 1), 9), other_size);
  EXPECT_FALSE(blender.addAlphaRuns(other_size));
  EXPECT_EQ(blender.added(), 0);
  std::vector<uint8_t> empty;
  blender.finish(empty);
  EXPECT_EQ(empty, std::vector<uint8_t>(w * h * 4, 0));
}

}  // namespace
}  // namespace lumistage
