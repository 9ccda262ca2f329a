// The picture of a fit: each camera's cells coloured by whether the body and the silhouette hold
// them, read back from the PNG written.
#include "core/eval/fit_picture.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "tests/test_util.h"

namespace lumistage {
namespace {

LowResSilhouette cells(int camera, int w, int h, int x0, int x1) {
  LowResSilhouette s;
  s.camera = camera, s.step = 4, s.width = w, s.height = h;
  s.bits.assign((size_t(w) * h + 7) / 8, 0);
  for (int y = 0; y < h; ++y)
    for (int x = x0; x < x1; ++x) s.set(x, y);
  return s;
}

TEST(FitPicture, ColoursEachCellByWhoHoldsIt) {
  // Two cameras of 8x6 cells over a white image: the silhouette holds columns 2-5, the body 4-7.
  const int w = 8, h = 6;
  std::vector<uint8_t> white(size_t(w) * 4 * h * 4 * 3, 255);
  const ImageView image{PixelFormat::kRgb8, w * 4, h * 4, white.data()};
  const LowResSilhouette a = cells(0, w, h, 2, 6), b = cells(1, w, h, 2, 6);
  std::vector<LowResSilhouette> body = {cells(0, w, h, 4, 8), LowResSilhouette{}};
  const auto path = testing::testFolder("fit_picture") / "fit.png";
  writeFitPicture(path, {image, image}, {&a, &b}, body);
  const cv::Mat picture = cv::imread(path.string(), cv::IMREAD_COLOR);  // BGR
  ASSERT_FALSE(picture.empty());
  EXPECT_EQ(picture.cols, 2 * w + 4);  // side by side, 4 pixels apart
  EXPECT_EQ(picture.rows, h);
  const auto at = [&](int x, int y) { return picture.at<cv::Vec3b>(y, x); };
  const auto dominant = [](const cv::Vec3b& p) {  // 0 blue, 1 green, 2 red, -1 grey
    if (p[0] == p[1] && p[1] == p[2]) return -1;
    return p[0] > p[1] && p[0] > p[2] ? 0 : p[1] > p[2] ? 1 : 2;
  };
  EXPECT_EQ(dominant(at(0, 3)), -1);  // neither: the image, dimmed
  EXPECT_LT(at(0, 3)[0], 255);
  EXPECT_EQ(dominant(at(3, 3)), 0);  // the silhouette only
  EXPECT_EQ(dominant(at(5, 3)), 1);  // both
  EXPECT_EQ(dominant(at(7, 3)), 2);  // the body only
  // The second camera has no body (nobody tracked there): its silhouette in blue.
  EXPECT_EQ(dominant(at(w + 4 + 5, 3)), 0);
  EXPECT_EQ(dominant(at(w + 4 + 7, 3)), -1);
}

}  // namespace
}  // namespace lumistage
