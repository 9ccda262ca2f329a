#include "core/render/lumigraph_weights.h"

#include <gtest/gtest.h>

#include <numeric>

#include "core/geometry/ring_rig.h"

namespace lumistage {
namespace {

std::vector<Eigen::Vector3d> ringCentres() {
  const Rig rig = makeRingRig({});
  std::vector<Eigen::Vector3d> centres;
  for (const Camera& c : rig.cameras()) centres.push_back(c.centre());
  return centres;
}

std::vector<double> normalised(std::vector<double> w) {
  const double sum = std::accumulate(w.begin(), w.end(), 0.0);
  for (double& v : w) v /= sum;
  return w;
}

TEST(LumigraphWeights, DesiredCameraOnAnInputCameraTakesItsImage) {
  const auto cameras = ringCentres();
  bool visible[12];
  std::fill(std::begin(visible), std::end(visible), true);
  const Eigen::Vector3d point(0.1, 0.05, 1.2);
  std::vector<double> w;
  for (size_t c = 0; c < cameras.size(); ++c) {
    const Eigen::Vector3d normal = (cameras[c] - point).normalized();  // a surface facing camera c
    lumigraphWeights(point, normal, cameras[c], cameras, visible, {}, w);
    const std::vector<double> blend = normalised(w);
    EXPECT_GT(blend[c], 0.999) << "camera " << c;
  }
}

TEST(LumigraphWeights, HiddenAndGrazingCamerasGetNothingAndAtMostKBlend) {
  const auto cameras = ringCentres();
  bool visible[12];
  std::fill(std::begin(visible), std::end(visible), true);
  visible[0] = false;  // occluded
  const Eigen::Vector3d point(0, 0, 1.2),
      normal(1, 0, 0);  // facing +x: cameras 0, 1, 11 (and 2, 10)
  const Eigen::Vector3d desired(3.0, 0.8, 1.5);
  std::vector<double> w;
  lumigraphWeights(point, normal, desired, cameras, visible, {}, w);
  EXPECT_EQ(w[0], 0.0);                                                          // hidden
  for (int behind : {3, 4, 5, 6, 7, 8, 9}) EXPECT_EQ(w[behind], 0.0) << behind;  // back-facing
  int blended = 0;
  for (double v : w) blended += v > 0;
  EXPECT_LE(blended, LumigraphWeightParams().k);
  EXPECT_GE(blended, 1);
  // The nearest in angle to the desired view weighs most.
  EXPECT_GT(w[1], w[11]);
}

TEST(LumigraphWeights, WeightsChangeSmoothlyAsTheDesiredCameraMoves) {
  const auto cameras = ringCentres();
  bool visible[12];
  std::fill(std::begin(visible), std::end(visible), true);
  const Eigen::Vector3d point(0, 0, 1.0), normal(0.8, 0.6, 0);
  std::vector<double> a, b;
  double worst = 0;
  for (double t = 0; t < 6.28; t += 0.01) {
    const Eigen::Vector3d d1(4 * std::cos(t), 4 * std::sin(t), 1.6),
        d2(4 * std::cos(t + 0.002), 4 * std::sin(t + 0.002), 1.6);
    lumigraphWeights(point, normal, d1, cameras, visible, {}, a);
    lumigraphWeights(point, normal, d2, cameras, visible, {}, b);
    const double sa = std::accumulate(a.begin(), a.end(), 0.0),
                 sb = std::accumulate(b.begin(), b.end(), 0.0);
    if (sa == 0 || sb == 0) continue;
    for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::abs(a[i] / sa - b[i] / sb));
  }
  EXPECT_LT(worst, 0.05);  // a 0.1 degree step never swaps the blend abruptly
}

TEST(LumigraphWeights, NodesPartialSumsNormaliseToTheSameBlend) {
  // The distributed blend: each node sums its own cameras' weighted colours and weights; the
  // studio divides by the total. Exactly the single-process blend.
  const auto cameras = ringCentres();
  bool visible[12];
  std::fill(std::begin(visible), std::end(visible), true);
  const Eigen::Vector3d point(0.2, -0.1, 1.3), normal = Eigen::Vector3d(1, 1, 0.2).normalized();
  std::vector<double> w;
  LumigraphWeightParams params;
  params.k = 4;
  lumigraphWeights(point, normal, Eigen::Vector3d(3, 3, 1.8), cameras, visible, params, w);
  std::vector<double> colour(12);
  for (int i = 0; i < 12; ++i) colour[i] = 10.0 * i;
  double single_num = 0, single_den = 0;
  for (int i = 0; i < 12; ++i) single_num += w[i] * colour[i], single_den += w[i];
  double num = 0, den = 0;
  for (int node = 0; node < 4; ++node) {  // node j owns cameras j, j+4, j+8
    double node_num = 0, alpha = 0;
    for (int i = node; i < 12; i += 4) node_num += w[i] * colour[i], alpha += w[i];
    num += node_num, den += alpha;  // the node sends colour = node_num / alpha and alpha
  }
  EXPECT_NEAR(num / den, single_num / single_den, 1e-12);
}

}  // namespace
}  // namespace lumistage
