#include "core/calib/wand_detector.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace lumistage {
namespace {

// A dark mono8 frame with sensor noise and Gaussian spots (an LED seen slightly out of focus).
Image darkFrame(int width, int height, const std::vector<Eigen::Vector2d>& spots, double sigma_px,
                uint32_t seed) {
  Image image;
  image.resize(PixelFormat::kMono8, width, height);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(12.0, 3.0);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      double v = noise(rng);
      for (const Eigen::Vector2d& s : spots) {
        const double d2 = (Eigen::Vector2d(x, y) - s).squaredNorm();
        v += 240 * std::exp(-d2 / (2 * sigma_px * sigma_px));
      }
      image.pixels[static_cast<size_t>(y) * width + x] =
          static_cast<uint8_t>(std::clamp(std::lround(v), 0L, 255L));
    }
  }
  return image;
}

TEST(WandDetector, FindsTheSpotToATenthOfAPixel) {
  WandDetector detector;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(20, 140);
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector2d truth(u(rng), u(rng) * 0.7);
    const WandDetection d = detector.detect(darkFrame(160, 120, {truth}, 2.0, i).view());
    ASSERT_EQ(d.status, WandDetection::Status::kFound);
    EXPECT_LT((d.pixel - truth).norm(), 0.1) << truth.transpose();
    EXPECT_GE(d.pixels, 9);
  }
}

TEST(WandDetector, RejectsTwoSpotsAndNone) {
  WandDetector detector;
  EXPECT_EQ(detector.detect(darkFrame(160, 120, {}, 1.5, 1).view()).status,
            WandDetection::Status::kNone);
  const WandDetection two =
      detector.detect(darkFrame(160, 120, {{40, 40}, {100, 70}}, 1.5, 2).view());
  EXPECT_EQ(two.status, WandDetection::Status::kAmbiguous);
  EXPECT_EQ(two.blobs, 2);
}

TEST(WandDetector, GivesUpOnABrightFrame) {
  Image lit;
  lit.resize(PixelFormat::kMono8, 160, 120);
  std::fill(lit.pixels.begin(), lit.pixels.end(), 250);
  EXPECT_EQ(WandDetector().detect(lit.view()).status, WandDetection::Status::kTooBright);
}

TEST(WandDetector, IgnoresHotPixels) {
  Image image = darkFrame(160, 120, {{80.3, 60.6}}, 1.5, 3);
  image.pixels[5 * 160 + 7] = 255;  // a lone hot pixel
  const WandDetection d = WandDetector().detect(image.view());
  ASSERT_EQ(d.status, WandDetection::Status::kFound);
  EXPECT_LT((d.pixel - Eigen::Vector2d(80.3, 60.6)).norm(), 0.1);
}

}  // namespace
}  // namespace lumistage
