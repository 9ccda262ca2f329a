// The lumigraph renderer on each kind of camera image (Bayer mosaics demosaiced or sampled as
// their cells, spill, monochrome), on a real headless OpenGL context.
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
#include "core/render/lumigraph_renderer.h"
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

// Bayer images demosaiced at full resolution: the desired camera on an input camera gives that
// camera's image as a camera's software shows it (its bilinear demosaic), nearly as finely as an
// RGB camera's (37.6 dB here); from the 2x2 cells, at half the resolution, 7 dB less. On a software
// renderer the cells are the default, on a GPU the full resolution.
TEST_F(LumigraphRendererTest, BayerImagesDemosaicedAtFullResolutionGiveTheCamerasImage) {
  std::vector<int> all;
  for (int c = 0; c < rig().cameraCount(); ++c) all.push_back(c);
  std::vector<Image> bayer(all.size());
  for (int c : all) {
    const Camera& camera = rig().camera(c);
    rgbaToImage(frame_->images[c].data(), camera.width(), camera.height(), PixelFormat::kBayerRggb8,
                bayer[c]);
  }
  const int c = 5;
  const Camera& camera = rig().camera(c);
  std::vector<uint8_t> shown(size_t(camera.width()) * camera.height() * 4);
  demosaicBayerToRgba(bayer[c].view(), shown.data());
  const auto score = [&](LumigraphParams::BayerImages how) {
    LumigraphParams params;
    params.bayer_images = how;
    LumigraphRenderer renderer(rig(), all, params);
    EXPECT_EQ(renderer.params().bayer_images, how);
    renderer.setMesh(frame_->surface.positions, frame_->surface.normals, frame_->surface.triangles);
    for (int k : all) renderer.setImage(k, bayer[k].view());
    std::vector<uint8_t> rendered;
    renderer.render(camera, rendered);
    return compareOverMask(rendered, shown, frame_->masks[c], camera.width(), camera.height());
  };
  const ViewScore full = score(LumigraphParams::BayerImages::kFullResolution);
  const ViewScore cells = score(LumigraphParams::BayerImages::kCells);
  EXPECT_GT(full.pixels, 10000);
  EXPECT_GT(full.psnr_db, 36.0);
  EXPECT_GT(full.ssim, 0.97);
  EXPECT_GT(full.psnr_db, cells.psnr_db + 5.0) << "cells: " << cells.psnr_db << " dB";
  // kAuto resolves by the renderer: cells in software, full resolution on a GPU.
  LumigraphRenderer automatic(rig(), {c});
  EXPECT_EQ(automatic.params().bayer_images, currentRendererIsSoftware()
                                                 ? LumigraphParams::BayerImages::kCells
                                                 : LumigraphParams::BayerImages::kFullResolution);
}

// At full resolution the shader demosaics the mosaic itself: the view equals the one rendered from
// the images demosaiced on the CPU (OpenCV) and uploaded as RGBA, pixel by pixel to rounding,
// with every camera in another of the four Bayer layouts (each camera's layout read apart), from an
// input camera and from between cameras.
TEST_F(LumigraphRendererTest, TheShadersDemosaicEqualsOpenCvs) {
  const PixelFormat layouts[] = {PixelFormat::kBayerRggb8, PixelFormat::kBayerGrbg8,
                                 PixelFormat::kBayerGbrg8, PixelFormat::kBayerBggr8};
  std::vector<int> all;
  for (int c = 0; c < rig().cameraCount(); ++c) all.push_back(c);
  LumigraphParams params;
  params.bayer_images = LumigraphParams::BayerImages::kFullResolution;
  // The images read as the weights' misregistration reads them would move a camera's weight by
  // a level's difference at an edge: the demosaic alone is compared here.
  params.misregistration_m = 0;
  LumigraphRenderer mosaics(rig(), all, params), demosaiced(rig(), all, params);
  for (LumigraphRenderer* r : {&mosaics, &demosaiced})
    r->setMesh(frame_->surface.positions, frame_->surface.normals, frame_->surface.triangles);
  for (int c : all) {
    const Camera& camera = rig().camera(c);
    Image bayer;
    rgbaToImage(frame_->images[c].data(), camera.width(), camera.height(), layouts[c % 4], bayer);
    mosaics.setImage(c, bayer.view());
    std::vector<uint8_t> rgba(size_t(camera.width()) * camera.height() * 4);
    demosaicBayerToRgba(bayer.view(), rgba.data());
    demosaiced.setImageRgba(c, rgba.data(), camera.width(), camera.height());
  }
  for (const Camera& view : {rig().camera(5), desiredView()}) {
    std::vector<uint8_t> a, b;
    mosaics.render(view, a);
    demosaiced.render(view, b);
    ASSERT_EQ(a.size(), b.size());
    int64_t pixels = 0;
    int worst = 0;
    for (size_t i = 0; i < a.size(); i += 4) {
      if (a[i + 3] == 0 && b[i + 3] == 0) continue;
      ++pixels;
      for (int k = 0; k < 4; ++k) worst = std::max(worst, std::abs(a[i + k] - b[i + k]));
    }
    EXPECT_GT(pixels, 5000) << view.name();
    // OpenCV rounds each demosaiced pixel before the filtered read, the shader interpolates first
    // (llvmpipe: at most 2 levels apart).
    EXPECT_LE(worst, 3) << view.name();
  }
}

// A Bayer image is sampled as the bilinear blend of its 2x2 cells' colours (R, the mean of the two
// G, B) at the texel: cells of known colours, mosaicked in two layouts, rendered from an input
// camera, against that blend computed here.
TEST_F(LumigraphRendererTest, BayerImagesAreSampledAsTheirCellsColours) {
  auto cellColour = [](int cx, int cy, int k) {
    const double v = k == 0   ? cx / 2.0                                    // a gentle ramp
                     : k == 1 ? 128 + 100 * std::sin(cx * 0.4 + cy * 0.25)  // steep waves
                              : 255 - cy / 2.0;
    return uint8_t(std::lround(std::clamp(v, 0.0, 255.0)));
  };
  const int render_camera = 5;
  for (PixelFormat format : {PixelFormat::kBayerRggb8, PixelFormat::kBayerGbrg8}) {
    std::vector<int> all;
    for (int c = 0; c < rig().cameraCount(); ++c) all.push_back(c);
    // The sampling alone: the pattern's waves make green the largest colour in places, which the
    // despill would limit where the other cameras colour the rim.
    LumigraphParams params;
    params.despill_angle_rad = 0;
    params.bayer_images = LumigraphParams::BayerImages::kCells;  // a GPU's default is the other
    LumigraphRenderer renderer(rig(), all, params);
    renderer.setMesh(frame_->surface.positions, frame_->surface.normals, frame_->surface.triangles);
    for (int c = 0; c < rig().cameraCount(); ++c) {
      const Camera& camera = rig().camera(c);
      std::vector<uint8_t> rgba(size_t(camera.width()) * camera.height() * 4, 255);
      for (int y = 0; y < camera.height(); ++y)
        for (int x = 0; x < camera.width(); ++x)
          for (int k = 0; k < 3; ++k)
            rgba[4 * (size_t(y) * camera.width() + x) + k] = cellColour(x / 2, y / 2, k);
      Image bayer;
      rgbaToImage(rgba.data(), camera.width(), camera.height(), format, bayer);
      renderer.setImage(c, bayer.view());
    }
    const Camera& camera = rig().camera(render_camera);
    std::vector<uint8_t> rendered;
    renderer.render(camera, rendered);
    const int cells_x = camera.width() / 2, cells_y = camera.height() / 2;
    double error = 0;
    int64_t pixels = 0, far_off = 0;
    for (int y = 0; y < camera.height(); ++y) {
      for (int x = 0; x < camera.width(); ++x) {
        const size_t i = size_t(y) * camera.width() + x;
        if (rendered[4 * i + 3] == 0 || !frame_->masks[render_camera][i]) continue;
        // Texel x + 0.5; cell centres at 2c + 1 texels.
        const double sx = (x - 0.5) / 2, sy = (y - 0.5) / 2;
        const int x0 = int(std::floor(sx)), y0 = int(std::floor(sy));
        const double fx = sx - x0, fy = sy - y0;
        const int xa = std::clamp(x0, 0, cells_x - 1), xb = std::clamp(x0 + 1, 0, cells_x - 1);
        const int ya = std::clamp(y0, 0, cells_y - 1), yb = std::clamp(y0 + 1, 0, cells_y - 1);
        for (int k = 0; k < 3; ++k) {
          const double expected =
              (1 - fy) * ((1 - fx) * cellColour(xa, ya, k) + fx * cellColour(xb, ya, k)) +
              fy * ((1 - fx) * cellColour(xa, yb, k) + fx * cellColour(xb, yb, k));
          const double d = std::abs(rendered[4 * i + k] - expected);
          error += d;
          far_off += d > 4;
        }
        ++pixels;
      }
    }
    ASSERT_GT(pixels, 10000);
    // Texture coordinates interpolated over triangles sit within a small fraction of a pixel of
    // the camera's own projection; the steep waves change by up to 20 levels a pixel.
    EXPECT_LT(error / (3 * pixels), 1.0) << int(format);
    EXPECT_LT(double(far_off) / (3 * pixels), 0.01) << int(format);
  }
}

// The screen's green spill: every camera's image a greenish grey (green above red and blue, as
// the screen's light makes the actor's edges). Seen from an input camera, the view keeps that
// camera's colour, spill and all; seen from elsewhere (the camera left out, or a view between
// cameras), green is limited to the larger of red and blue; with the despill off, it is not.
TEST_F(LumigraphRendererTest, SpillIsKeptFromAnInputCameraAndLimitedFromElsewhere) {
  const std::array<uint8_t, 4> spilled = {90, 150, 70, 255};
  const auto render = [&](float despill_angle, const Camera& view, int left_out) {
    std::vector<int> all;
    for (int c = 0; c < rig().cameraCount(); ++c) all.push_back(c);
    LumigraphParams params;
    params.despill_angle_rad = despill_angle;
    LumigraphRenderer renderer(rig(), all, params);
    renderer.setMesh(frame_->surface.positions, frame_->surface.normals, frame_->surface.triangles);
    for (int c = 0; c < rig().cameraCount(); ++c) {
      const Camera& camera = rig().camera(c);
      std::vector<uint8_t> rgba(size_t(camera.width()) * camera.height() * 4);
      for (size_t i = 0; i < rgba.size(); i += 4)
        std::copy(spilled.begin(), spilled.end(), &rgba[i]);
      renderer.setImageRgba(c, rgba.data(), camera.width(), camera.height());
    }
    std::vector<bool> active(size_t(rig().cameraCount()), true);
    if (left_out >= 0) active[size_t(left_out)] = false;
    renderer.setActive(active);
    std::vector<uint8_t> rendered;
    renderer.render(view, rendered);
    // The drawn pixels' mean red, green and blue.
    std::array<double, 3> mean = {0, 0, 0};
    int64_t drawn = 0;
    for (size_t i = 0; i < rendered.size(); i += 4) {
      if (rendered[i + 3] == 0) continue;
      ++drawn;
      for (int k = 0; k < 3; ++k) mean[k] += rendered[i + k];
    }
    EXPECT_GT(drawn, 5000);
    for (double& m : mean) m /= double(std::max<int64_t>(drawn, 1));
    return mean;
  };
  const float on = LumigraphParams().despill_angle_rad;
  ASSERT_GT(on, 0.0f);
  const Camera& input = rig().camera(4);
  for (const auto& [view, left_out] : {std::pair{input, -1}, std::pair{input, 4}}) {
    const std::array<double, 3> despilled = render(on, view, left_out);
    const std::array<double, 3> kept = render(0, view, left_out);
    SCOPED_TRACE(left_out < 0 ? "from the input camera" : "from the input camera, left out");
    EXPECT_NEAR(kept[1], 150, 1.0);
    EXPECT_NEAR(despilled[0], 90, 1.0);
    EXPECT_NEAR(despilled[2], 70, 1.0);
    if (left_out < 0) {
      // The camera's own view: its spill is what it sees (the rim it does not see, a few per cent
      // of the pixels, is the other cameras', despilled).
      EXPECT_GT(despilled[1], 145);
    } else {
      EXPECT_NEAR(despilled[1], 90, 1.0);  // the others' spill is theirs
    }
  }
  EXPECT_NEAR(render(on, desiredView(), -1)[1], 90, 1.0);

  // Between the two: camera 4 turned about the stage's vertical through the mesh's centre, so
  // that the rays from the centre to it and to camera 4 are about a third of the angle apart
  // (where the smoothstep is not the straight ramp). A
  // renderer of camera 4 alone colours every pixel it draws with that camera's colour, its green
  // limited by smoothstep(0, angle, their angle), the same everywhere.
  LumigraphParams flat;  // the mesh's centre: the mean of the vertices drawn
  flat.phong_subdivision = false;
  LumigraphRenderer alone(rig(), {4}, flat);
  alone.setMesh(frame_->surface.positions, frame_->surface.normals, frame_->surface.triangles);
  std::vector<uint8_t> rgba(size_t(input.width()) * input.height() * 4);
  for (size_t i = 0; i < rgba.size(); i += 4) std::copy(spilled.begin(), spilled.end(), &rgba[i]);
  alone.setImageRgba(0, rgba.data(), input.width(), input.height());
  const Eigen::Vector3d centre = frame_->surface.positions.cast<double>().rowwise().mean();
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(0.3 * on, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d moved = centre + turn * (input.centre() - centre);
  const Eigen::Matrix3d R = input.rotation() * turn.transpose();
  const Camera between("between", input.width(), input.height(), input.intrinsics(),
                       input.distortion(), R, -R * moved);
  const Eigen::Vector3d a = input.centre() - centre, b = moved - centre;
  const double t = std::atan2(a.cross(b).norm(), a.dot(b)) / on;
  ASSERT_GT(t, 0.15);
  ASSERT_LT(t, 0.4);
  const double limited = 150 - t * t * (3 - 2 * t) * (150 - 90);
  std::vector<uint8_t> rendered;
  alone.render(between, rendered);
  int64_t drawn = 0, off = 0;
  for (size_t i = 0; i < rendered.size(); i += 4) {
    if (rendered[i + 3] == 0) continue;
    ++drawn;
    off += std::abs(rendered[i + 1] - limited) > 1.0 || rendered[i] != 90 || rendered[i + 2] != 70;
  }
  EXPECT_GT(drawn, 5000);
  EXPECT_EQ(off, 0) << "green " << limited;
}

// A monochrome camera's picture is grey, pixel by pixel: rendered from that camera, every drawn
// pixel is grey and its level the picture's there (read as a Bayer mosaic, the edges between grey
// pixels took false colour).
TEST_F(LumigraphRendererTest, MonochromeImagesStayGrey) {
  const int c = 5;
  const Camera& camera = rig().camera(c);
  auto renderer = makeRenderer({c});
  Image grey;
  grey.resize(PixelFormat::kMono8, camera.width(), camera.height());
  for (size_t i = 0; i < grey.pixels.size(); ++i) {
    const uint8_t* rgba = &frame_->images[c][4 * i];
    grey.pixels[i] = uint8_t((rgba[0] + 2 * rgba[1] + rgba[2]) / 4);
  }
  renderer->setImage(0, grey.view());
  std::vector<uint8_t> rendered;
  renderer->render(camera, rendered);
  int64_t drawn = 0, coloured = 0, off = 0;
  for (size_t i = 0; i < grey.pixels.size(); ++i) {
    const uint8_t* p = &rendered[4 * i];
    if (p[3] == 0 || !frame_->masks[c][i]) continue;
    ++drawn;
    coloured += p[0] != p[1] || p[1] != p[2];
    off += std::abs(int(p[1]) - int(grey.pixels[i])) > 8;
  }
  ASSERT_GT(drawn, 10000);
  EXPECT_EQ(coloured, 0);
  EXPECT_LT(off, drawn / 50);
}

}  // namespace
}  // namespace lumistage
