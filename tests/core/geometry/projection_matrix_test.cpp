#include "core/geometry/projection_matrix.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/core/geometry/test_cameras.h"

namespace lumistage {
namespace {

TEST(ProjectionMatrix, DecompositionRecoversRandomCamerasAtAnyScale) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> scale(0.01, 100);
  for (int trial = 0; trial < 200; ++trial) {
    const Camera camera = testing::randomCamera(rng, false, /*skewed=*/true);
    const double s = (trial % 2 ? -1 : 1) * scale(rng);  // either sign: P is projective
    const DecomposedProjection d = decomposeProjection(s * camera.projectionMatrix());
    EXPECT_LT((d.K - camera.intrinsics().matrix()).norm(), 1e-9 * camera.intrinsics().fx);
    EXPECT_LT((d.R - camera.rotation()).norm(), 1e-9);
    EXPECT_LT((d.t - camera.translation()).norm(), 1e-9);
    EXPECT_NEAR(d.R.determinant(), 1.0, 1e-12);
    EXPECT_NEAR(d.K(2, 2), 1.0, 1e-15);
  }
}

TEST(ProjectionMatrix, SingularMatrixIsRejected) {
  Eigen::Matrix<double, 3, 4> P;
  P << 1, 2, 3, 4, 2, 4, 6, 8, 0, 0, 1, 1;  // rows 1 and 2 dependent
  try {
    decomposeProjection(P);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("singular"), std::string::npos);
  }
  P.setZero();
  EXPECT_THROW(decomposeProjection(P), std::invalid_argument);
  P(0, 0) = std::nan("");
  EXPECT_THROW(decomposeProjection(P), std::invalid_argument);
}

}  // namespace
}  // namespace lumistage
