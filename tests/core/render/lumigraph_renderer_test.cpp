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
#include "tests/test_util.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

// One frame of the reference studio (12 cameras, 1024x768), rendered once for every test.
class LumigraphRendererTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    StudioConfig config =
        loadStudioConfig(fs::path(LUMISTAGE_TEST_RESOURCE_DIR) / "studio" / "reference.yaml");
    studio_ = new VirtualStudio(config, 12);
    frame_ = new StudioFrame;
    studio_->renderFrame(10, *frame_);
    frame_->surface.computeNormals();
  }
  static void TearDownTestSuite() {
    delete frame_;
    delete studio_;
  }
  const Rig& rig() const { return studio_->rig(); }
  // A renderer of `own` cameras (all when empty) with the frame's surface and images.
  std::unique_ptr<LumigraphRenderer> makeRenderer(std::vector<int> own = {},
                                                  const LumigraphParams& params = {}) const {
    if (own.empty())
      for (int c = 0; c < rig().cameraCount(); ++c) own.push_back(c);
    auto r = std::make_unique<LumigraphRenderer>(rig(), own, params);
    r->setMesh(frame_->surface.positions, frame_->surface.normals, frame_->surface.triangles);
    for (size_t j = 0; j < own.size(); ++j) {
      const Camera& c = rig().camera(own[j]);
      r->setImageRgba(static_cast<int>(j), frame_->images[own[j]].data(), c.width(), c.height());
    }
    return r;
  }
  // A virtual camera between cameras 0 and 1 (not on any input camera), smaller.
  Camera desiredView() const {
    const Camera& a = rig().camera(0);
    const Camera& b = rig().camera(1);
    return lookingAtTheActor(0.5 * (a.centre() + b.centre()));
  }
  // A virtual camera at `centre` looking at the middle of the stage, a metre up.
  static Camera lookingAtTheActor(const Eigen::Vector3d& centre) {
    const Eigen::Vector3d z = (Eigen::Vector3d(0, 0, 1.0) - centre).normalized();
    const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
    Eigen::Matrix3d R;
    R.row(0) = x;
    R.row(1) = z.cross(x);
    R.row(2) = z;
    return Camera("desired", 480, 360, {400, 400, 239.5, 179.5, 0}, {}, R, -R * centre);
  }
  static VirtualStudio* studio_;
  static StudioFrame* frame_;
};

VirtualStudio* LumigraphRendererTest::studio_ = nullptr;
StudioFrame* LumigraphRendererTest::frame_ = nullptr;

int64_t covered(const std::vector<uint8_t>& rgba) {
  int64_t n = 0;
  for (size_t i = 3; i < rgba.size(); i += 4) n += rgba[i] > 0;
  return n;
}

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
  const std::vector<uint16_t> all(visibility.masks().size(), 0xffff);
  renderer->setMesh(surface.positions, surface.normals, surface.triangles, all);
  renderer->render(desiredView(), unoccluded);
  const Camera view = desiredView();
  const std::vector<uint8_t> all_pixels(size_t(view.width()) * view.height(), 1);
  const ViewScore score = compareOverMask(unoccluded, own, all_pixels, view.width(), view.height());
  std::printf("  no occlusion against the visibility masks: %.1f dB\n", score.psnr_db);
  EXPECT_LT(score.psnr_db, 50.0);
  const std::vector<uint16_t> short_masks(10, 0xffff);
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
