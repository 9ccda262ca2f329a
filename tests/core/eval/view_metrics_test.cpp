// Scores of a rendered view against a camera's image: what the mask-only score ignores and the
// matte score counts.
#include "core/eval/view_metrics.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/base/error.h"

namespace lumistage {
namespace {

double psnr(double squared, int values) {
  return 10 * std::log10(255.0 * 255.0 / (squared / values));
}

TEST(ViewMetrics, MatteScoreCountsPixelsDrawnBeyondTheActorAndLeftUndrawn) {
  // A 4x1 strip: the actor at pixels 0-2, pixel 3 the screen.
  const int w = 4, h = 1;
  const std::vector<uint8_t> mask{1, 1, 1, 0};
  std::vector<uint8_t> truth(16, 0), rendered(16, 0);
  for (int i = 0; i < 4; ++i) {
    truth[4 * i] = truth[4 * i + 1] = truth[4 * i + 2] = 100, truth[4 * i + 3] = 255;
  }
  truth[12 + 1] = 200;  // the screen is green
  // Pixel 0 drawn 10 levels off in red, pixel 1 exact, pixel 2 left undrawn (alpha 0).
  for (int i : {0, 1}) {
    rendered[4 * i] = rendered[4 * i + 1] = rendered[4 * i + 2] = 100, rendered[4 * i + 3] = 255;
  }
  rendered[0] = 110;
  ViewScore score = compareOverMask(rendered, truth, mask, w, h);
  EXPECT_EQ(score.pixels, 3);
  // Over the mask: 10² + 3·100² (the undrawn pixel is black) over 3 pixels' 9 values.
  EXPECT_NEAR(score.psnr_db, psnr(100 + 3 * 100 * 100, 9), 1e-9);
  EXPECT_NEAR(score.matte_psnr_db, score.psnr_db, 1e-9);  // nothing drawn beyond the actor
  EXPECT_NEAR(score.missed_pct, 100.0 / 3, 1e-9);
  EXPECT_EQ(score.beyond_pct, 0);

  // The screen pixel drawn in the screen's own colour, at a renderer's alpha of one half: the
  // mask-only score does not see it; the matte compares it with black, whole, as the studio's
  // blend shows every drawn pixel (a renderer's alpha is a share of weight, not coverage).
  rendered[12] = 100, rendered[13] = 200, rendered[14] = 100, rendered[15] = 128;
  score = compareOverMask(rendered, truth, mask, w, h);
  EXPECT_NEAR(score.psnr_db, psnr(100 + 3 * 100 * 100, 9), 1e-9);
  const double beyond = std::pow(100, 2) * 2 + std::pow(200, 2);
  EXPECT_NEAR(score.matte_psnr_db, psnr(100 + 3 * 100 * 100 + beyond, 12), 1e-9);
  EXPECT_NEAR(score.beyond_pct, 100.0 / 3, 1e-9);
  EXPECT_LT(score.matte_psnr_db, score.psnr_db);
}

// No actor in the view (an empty mask): nothing over the mask is measured (NaN, which the means
// leave out, not 0 dB); the matte still charges the pixels drawn.
TEST(ViewMetrics, AViewWithoutTheActorIsNotScoredOverTheMask) {
  const std::vector<uint8_t> mask(4, 0), truth(16, 0);
  std::vector<uint8_t> rendered(16, 0);
  ViewScore score = compareOverMask(rendered, truth, mask, 4, 1);
  EXPECT_EQ(score.pixels, 0);
  EXPECT_TRUE(std::isnan(score.psnr_db));
  EXPECT_TRUE(std::isnan(score.ssim));
  EXPECT_TRUE(std::isnan(score.matte_psnr_db));  // nothing drawn either
  rendered[0] = 255, rendered[3] = 255;          // one red pixel drawn
  score = compareOverMask(rendered, truth, mask, 4, 1);
  EXPECT_NEAR(score.matte_psnr_db, psnr(255.0 * 255.0, 3), 1e-9);
}

TEST(ViewMetrics, RefusesImagesOfAnotherSize) {
  const std::vector<uint8_t> mask(4, 1), image(16, 0), small(12, 0);
  EXPECT_THROW(compareOverMask(small, image, mask, 4, 1), Error);
}

}  // namespace
}  // namespace lumistage
