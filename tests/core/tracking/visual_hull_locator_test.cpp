// Finding the actor from low-resolution silhouettes, against the virtual studio's truth.
#include "core/tracking/visual_hull_locator.h"

#include <gtest/gtest.h>

#include "core/body/human_skeleton.h"
#include "core/geometry/ring_rig.h"
#include "core/sim/virtual_studio.h"
#include "tests/core/sim/reference_studio.h"

namespace lumistage {
namespace {

TEST(VisualHullLocator, FindsTheWalkingActorFromSilhouettes) {
  VirtualStudio studio(testing::referenceStudio(3000), 60);
  const Rig& rig = studio.rig();
  const VisualHullLocator locator(rig, 8);
  StudioFrame frame;
  std::vector<Image> images(rig.cameraCount());
  std::vector<LowResSilhouette> silhouettes(rig.cameraCount());
  for (int f : {15, 45}) {
    studio.renderFrame(f, frame);
    std::vector<const LowResSilhouette*> all, half;
    for (int c = 0; c < rig.cameraCount(); ++c) {
      rgbaToImage(frame.images[c].data(), rig.camera(c).width(), rig.camera(c).height(),
                  PixelFormat::kBayerRggb8, images[c]);
      computeSilhouette(GreenScreenKeyer(), images[c].view(), c, 8, silhouettes[c]);
      all.push_back(&silhouettes[c]);
      if (c % 2 == 0) half.push_back(&silhouettes[c]);  // a node or two missing
    }
    const Eigen::Vector3d pelvis = frame.joints[kPelvis];
    const double top = frame.surface.positions.row(2).maxCoeff();
    for (const auto* cameras : {&all, &half}) {
      const ActorLocation where = locator.locate(*cameras);
      ASSERT_TRUE(where.found) << "frame " << f;
      EXPECT_LT((where.centroid.head<2>() - pelvis.head<2>()).norm(), 0.08) << "frame " << f;
      EXPECT_NEAR(where.upper.z(), top, 0.15) << "frame " << f;
      EXPECT_LT(where.lower.z(), 0.1) << "frame " << f;
    }
  }
  // One camera alone cannot place anything.
  EXPECT_FALSE(locator.locate({&silhouettes[0]}).found);
}

TEST(VisualHullLocator, NodeSilhouettesAreTheKeyOfEveryCell) {
  // A node's Bayer cameras take a path of their own (steps of 4 and 8; at 4, eight cells at a
  // time in SSE2); it gives keyCell's result at every cell, in every layout, on an image where the
  // key is close to its threshold in many cells (so that the window's weights decide), as does any
  // other format or step. 72 pixels: rows of 18 cells at step 4, so that most rows begin inside a
  // byte of the bits and end with cells the eight at a time leave.
  for (const auto& [width, height] : {std::pair{64, 48}, std::pair{72, 44}}) {
    std::vector<uint8_t> rgba(size_t(width) * height * 4);
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        uint8_t* p = &rgba[4 * (size_t(y) * width + x)];
        const int wave = (x * 7 + y * 13 + (x * y) % 11) % 60;
        p[0] = uint8_t(60 + wave), p[1] = uint8_t(80 + (x * 5 + y * 3) % 70),
        p[2] = uint8_t(50 + (x + 2 * y) % 40), p[3] = 255;
      }
    }
    const GreenScreenKeyer keyer(25);
    for (PixelFormat format : kAllPixelFormats) {
      Image image;
      rgbaToImage(rgba.data(), width, height, format, image);
      for (int step : {2, 4, 8}) {
        LowResSilhouette s;
        computeSilhouette(keyer, image.view(), 0, step, s);
        int set = 0;
        for (int y = 0; y < s.height; ++y) {
          for (int x = 0; x < s.width; ++x) {
            EXPECT_EQ(s.at(x, y), keyCell(keyer, image.view(), x, y, step))
                << pixelFormatName(format) << " " << width << "x" << height << " step " << step
                << " cell " << x << "," << y;
            set += s.at(x, y);
          }
        }
        if (format == PixelFormat::kMono8) continue;  // grey: no green excess, all the actor
        EXPECT_GT(set, 0) << pixelFormatName(format) << " step " << step;
        EXPECT_LT(set, s.width * s.height) << pixelFormatName(format) << " step " << step;
      }
    }
    // Every threshold the cells' excesses cross, so that a cell whose mean is rounded otherwise
    // than keyCell rounds it flips somewhere.
    for (PixelFormat format : {PixelFormat::kRgb8, PixelFormat::kBayerRggb8}) {
      Image image;
      rgbaToImage(rgba.data(), width, height, format, image);
      for (int threshold = -60; threshold <= 60; ++threshold) {
        const GreenScreenKeyer at(threshold);
        for (int step : {4, 8}) {
          LowResSilhouette s;
          computeSilhouette(at, image.view(), 0, step, s);
          for (int y = 0; y < s.height; ++y)
            for (int x = 0; x < s.width; ++x)
              ASSERT_EQ(s.at(x, y), keyCell(at, image.view(), x, y, step))
                  << pixelFormatName(format) << " threshold " << threshold << " step " << step
                  << " cell " << x << "," << y;
        }
      }
    }
    // Thresholds beyond any green excess (a keyer made by hand) key every cell alike, in 16 bits
    // too: all the actor, or none of it.
    Image bayer;
    rgbaToImage(rgba.data(), width, height, PixelFormat::kBayerRggb8, bayer);
    for (const int threshold : {40000, -40000}) {
      LowResSilhouette s;
      computeSilhouette(GreenScreenKeyer(threshold), bayer.view(), 0, 4, s);
      int set = 0;
      for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < s.width; ++x) set += s.at(x, y);
      EXPECT_EQ(set, threshold > 0 ? s.width * s.height : 0) << "threshold " << threshold;
    }
  }
}

TEST(VisualHullLocator, SilhouetteBitsAreTheKeyAtCellCentres) {
  // A 32x16 Bayer image, green except a block: cells inside the block are set.
  Image image;
  image.resize(PixelFormat::kBayerRggb8, 32, 16);
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 32; ++x) {
      const bool block = x >= 8 && x < 16 && y >= 4 && y < 12;
      const bool green = (x + y) % 2 == 1;
      image.pixels[size_t(y) * 32 + x] = block ? 120 : (green ? 160 : 40);
    }
  }
  LowResSilhouette s;
  computeSilhouette(GreenScreenKeyer(), image.view(), 3, 4, s);
  EXPECT_EQ(s.camera, 3);
  ASSERT_EQ(s.width, 8);
  ASSERT_EQ(s.height, 4);
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 8; ++x)
      EXPECT_EQ(s.at(x, y), x >= 2 && x < 4 && y >= 1 && y < 3) << x << "," << y;
  }
  // The lumigraph's foreground mask: the same cells, a byte each.
  std::vector<uint8_t> mask(3, 7);
  silhouetteMask(s, mask);
  ASSERT_EQ(mask.size(), 32u);
  for (int i = 0; i < 32; ++i) EXPECT_EQ(mask[i], s.at(i % 8, i / 8) ? 255 : 0) << i;
}

// A 20 x 20 m box (the largest a rig file may give) is refused in words before anything is
// allocated for it: the studio builds the locator first, before the tracker checks its tables.
TEST(VisualHullLocator, RefusesABoxTooLargeForItsTables) {
  const Rig rig = makeRingRig({});
  try {
    const VisualHullLocator locator(rig, 4, 0.06, StageBox{{-10, -10, 0}, {10, 10, 5}});
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("give the rig file a smaller `stage`"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace lumistage
