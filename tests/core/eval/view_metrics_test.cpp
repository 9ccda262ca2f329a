// Scores of a rendered view against a camera's image: what the mask-only score ignores and the
// matte score counts.
#include "core/eval/view_metrics.h"

#include <gtest/gtest.h>

#include <array>
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
  // The undrawn pixel holds 3·100² of the 10² + 3·100² squared error.
  EXPECT_NEAR(score.missed_error_pct, 100.0 * 3e4 / (100 + 3e4), 1e-9);

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
  EXPECT_NEAR(score.missed_error_pct, 100.0 * 3e4 / (100 + 3e4), 1e-9);  // the mask's alone

  // Every pixel of the actor drawn: none of the error is on missed pixels.
  rendered[8] = rendered[9] = rendered[10] = 90, rendered[11] = 255;
  score = compareOverMask(rendered, truth, mask, w, h);
  EXPECT_EQ(score.missed_pct, 0);
  EXPECT_EQ(score.missed_error_pct, 0);
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
  ComparisonPicture picture;
  EXPECT_THROW(comparisonPicture(small, image, mask, 4, 1, picture), Error);
}

// The picture a person looks at: the render, the camera's image and the error map side by side,
// cropped to the actor and what was drawn, with a margin. In a 100x60 view the actor covers
// x 40-49, y 20-29; the render draws x 42-51 (two columns beyond the actor, two missed), its
// first drawn column 30 levels off.
TEST(ViewMetrics, AComparisonPictureShowsTheErrorsWhereTheyAre) {
  const int w = 100, h = 60, m = ComparisonPicture::kPictureMargin;
  std::vector<uint8_t> mask(size_t(w) * h, 0), truth(size_t(w) * h * 4, 0),
      rendered(size_t(w) * h * 4, 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      truth[4 * i + 1] = 200, truth[4 * i + 3] = 255;  // the screen
      if (y < 20 || y > 29) continue;
      if (x >= 40 && x <= 49) {
        mask[i] = 255;
        truth[4 * i] = 100, truth[4 * i + 1] = 100, truth[4 * i + 2] = 100;
      }
      if (x >= 42 && x <= 51) {
        rendered[4 * i] = rendered[4 * i + 1] = rendered[4 * i + 2] = x == 42 ? 130 : 100;
        rendered[4 * i + 3] = 255;
      }
    }
  ComparisonPicture picture;
  comparisonPicture(rendered, truth, mask, w, h, picture);
  const int panel = (51 + m) - (40 - m) + 1;
  ASSERT_EQ(picture.width, 3 * panel);
  ASSERT_EQ(picture.height, (29 + m) - (20 - m) + 1);
  ASSERT_EQ(picture.rgb.size(), size_t(picture.width) * picture.height * 3);
  // The view's (x, y) in panel p (0 render, 1 image, 2 errors).
  const auto at = [&](int p, int x, int y) {
    const uint8_t* c =
        &picture.rgb[(size_t(y - (20 - m)) * picture.width + p * panel + (x - (40 - m))) * 3];
    return std::array<int, 3>{c[0], c[1], c[2]};
  };
  using C = std::array<int, 3>;
  EXPECT_EQ(at(0, 45, 25), (C{100, 100, 100}));
  EXPECT_EQ(at(0, 40, 25), (C{0, 0, 0}));        // undrawn: black
  EXPECT_EQ(at(1, 40, 25), (C{100, 100, 100}));  // the camera's image
  EXPECT_EQ(at(1, 30, 25), (C{0, 200, 0}));
  EXPECT_EQ(at(2, 40, 25), (C{255, 0, 0}));      // missed: red
  EXPECT_EQ(at(2, 51, 25), (C{0, 128, 255}));    // beyond the actor: blue
  EXPECT_EQ(at(2, 42, 25), (C{120, 120, 120}));  // 30 levels off in each channel, four times
  EXPECT_EQ(at(2, 45, 25), (C{0, 0, 0}));        // exact
  EXPECT_EQ(at(2, 30, 25), (C{0, 0, 0}));        // the screen, not drawn
}

}  // namespace
}  // namespace lumistage
