#include "core/geometry/camera.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "tests/core/geometry/test_cameras.h"

namespace lumistage {
namespace {

TEST(Camera, UnprojectThenProjectReturnsThePixelWithDistortion) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 50; ++trial) {
    const Camera camera = testing::randomCamera(rng, /*distorted=*/true, /*skewed=*/true);
    std::uniform_real_distribution<double> px(0, camera.width() - 1), py(0, camera.height() - 1);
    std::uniform_real_distribution<double> depth(0.5, 8);
    for (int i = 0; i < 20; ++i) {
      const Eigen::Vector2d pixel(px(rng), py(rng));
      const std::optional<Ray> ray = camera.unproject(pixel);
      ASSERT_TRUE(ray) << "pixel " << pixel.transpose();
      EXPECT_NEAR(ray->direction.norm(), 1.0, 1e-12);
      EXPECT_LT((ray->origin - camera.centre()).norm(), 1e-12);
      const Eigen::Vector3d point = ray->origin + depth(rng) * ray->direction;
      const std::optional<Eigen::Vector2d> back = camera.project(point);
      ASSERT_TRUE(back);
      EXPECT_LT((*back - pixel).norm(), 1e-8) << "pixel " << pixel.transpose();
    }
  }
}

TEST(Camera, ProjectThenUnprojectGivesARayThroughThePoint) {
  std::mt19937 rng(2);
  for (int trial = 0; trial < 50; ++trial) {
    const Camera camera = testing::randomCamera(rng, true);
    std::uniform_real_distribution<double> u(-0.8, 0.8);
    const Eigen::Vector3d point(u(rng), u(rng), 1 + u(rng));
    const std::optional<Eigen::Vector2d> pixel = camera.project(point);
    ASSERT_TRUE(pixel);
    if (!camera.inImage(*pixel)) continue;  // the lens model is only valid on the image
    const std::optional<Ray> ray = camera.unproject(*pixel);
    ASSERT_TRUE(ray);
    const Eigen::Vector3d to_point = point - ray->origin;
    const double off_ray = (to_point - to_point.dot(ray->direction) * ray->direction).norm();
    EXPECT_LT(off_ray, 1e-9);
  }
}

TEST(Camera, DistortThenUndistortRoundTripsAcrossTheImage) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 30; ++trial) {
    const Camera camera = testing::randomCamera(rng, true, true);
    for (int gy = 0; gy <= 8; ++gy) {
      for (int gx = 0; gx <= 8; ++gx) {
        const Eigen::Vector2d distorted((camera.width() - 1) * gx / 8.0,
                                        (camera.height() - 1) * gy / 8.0);
        const std::optional<Eigen::Vector2d> ideal = camera.undistortPixel(distorted);
        ASSERT_TRUE(ideal) << distorted.transpose();
        EXPECT_LT((camera.distortPixel(*ideal) - distorted).norm(), 1e-8);
      }
    }
  }
}

TEST(Camera, DistortionMatchesOpenCvFormulaAtAKnownPoint) {
  // Hand-computed: x = 0.3, y = -0.2, r2 = 0.13.
  const Distortion d{-0.2, 0.05, 0.001, -0.002, 0.01};
  const double r2 = 0.13, radial = 1 + -0.2 * r2 + 0.05 * r2 * r2 + 0.01 * r2 * r2 * r2;
  const double xd = 0.3 * radial + 2 * 0.001 * 0.3 * -0.2 + -0.002 * (r2 + 2 * 0.09);
  const double yd = -0.2 * radial + 0.001 * (r2 + 2 * 0.04) + 2 * -0.002 * 0.3 * -0.2;
  const Eigen::Vector2d out = d.apply(Eigen::Vector2d(0.3, -0.2));
  EXPECT_DOUBLE_EQ(out.x(), xd);
  EXPECT_DOUBLE_EQ(out.y(), yd);
}

TEST(Camera, UndistortionFailsOutsideTheMonotonicField) {
  // Strong barrel distortion folds back beyond r ~ 1.3; a point far beyond has no inverse.
  const Distortion d{-0.3, 0, 0, 0, 0};
  EXPECT_TRUE(d.remove(Eigen::Vector2d(0.5, 0.2)));
  EXPECT_FALSE(d.remove(Eigen::Vector2d(5.0, 4.0)));
}

TEST(Camera, CentreAndViewingDirectionAgreeWithTheProjection) {
  std::mt19937 rng(4);
  for (int trial = 0; trial < 20; ++trial) {
    const Camera camera = testing::randomCamera(rng, true, true);
    EXPECT_LT(camera.toCamera(camera.centre()).norm(), 1e-12);
    // A point straight ahead lands on the principal point (distortion is zero on the axis).
    const std::optional<Eigen::Vector2d> pixel =
        camera.project(camera.centre() + 2.5 * camera.viewingDirection());
    ASSERT_TRUE(pixel);
    EXPECT_NEAR(pixel->x(), camera.intrinsics().cx, 1e-9);
    EXPECT_NEAR(pixel->y(), camera.intrinsics().cy, 1e-9);
    // And a point behind the camera projects nowhere.
    EXPECT_FALSE(camera.project(camera.centre() - camera.viewingDirection()));
  }
}

TEST(Camera, ProjectionMatrixMatchesProjectWithoutDistortion) {
  std::mt19937 rng(5);
  const Camera camera = testing::randomCamera(rng, false, true);
  const Eigen::Matrix<double, 3, 4> P = camera.projectionMatrix();
  const Eigen::Vector3d point(0.2, -0.1, 1.3);
  const Eigen::Vector3d h = P * point.homogeneous();
  EXPECT_LT((h.hnormalized() - *camera.project(point)).norm(), 1e-9);
}

TEST(Camera, BatchProjectionEqualsSingleProjectionInDoubleAndFloat) {
  std::mt19937 rng(6);
  const Camera camera = testing::randomCamera(rng, true, true);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::Matrix3Xd points(3, 500);
  for (int i = 0; i < points.cols(); ++i)
    points.col(i) = Eigen::Vector3d(u(rng), u(rng), 1 + u(rng));
  points.col(0) = camera.centre() - camera.viewingDirection();  // behind the camera

  Eigen::Matrix2Xd pixels;
  Eigen::VectorXd depths;
  camera.project(points, pixels, depths);
  Eigen::Matrix2Xf pixels_f;
  Eigen::VectorXf depths_f;
  camera.project(Eigen::Matrix3Xf(points.cast<float>()), pixels_f, depths_f);
  ASSERT_EQ(pixels.cols(), points.cols());
  EXPECT_LT(depths(0), 0);
  for (int i = 1; i < points.cols(); ++i) {
    const std::optional<Eigen::Vector2d> single = camera.project(points.col(i));
    ASSERT_TRUE(single);
    EXPECT_GT(depths(i), 0);
    EXPECT_LT((pixels.col(i) - *single).norm(), 1e-9);
    EXPECT_LT((pixels_f.col(i).cast<double>() - *single).norm(), 0.05);  // float: ~1e-7 relative
  }
}

TEST(Camera, RejectsInvalidParametersNamingTheCamera) {
  const Intrinsics k{800, 800, 512, 384, 0};
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const Eigen::Vector3d t(0, 0, 3);
  auto message = [](auto&& make) {
    try {
      make();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message([&] {
              Camera("c1", 1024, 768, {-800, 800, 512, 384, 0}, {}, I, t);
            }).find("camera 'c1': focal length fx must be a positive number"),
            std::string::npos);
  EXPECT_NE(message([&] { Camera("c1", 0, 768, k, {}, I, t); }).find("image size must be positive"),
            std::string::npos);
  Eigen::Matrix3d scaled = 2 * I;
  EXPECT_NE(message([&] { Camera("c1", 1024, 768, k, {}, scaled, t); }).find("not orthonormal"),
            std::string::npos);
  Eigen::Matrix3d reflection = I;
  reflection(2, 2) = -1;
  EXPECT_NE(message([&] { Camera("c1", 1024, 768, k, {}, reflection, t); }).find("reflection"),
            std::string::npos);
  EXPECT_NE(message([&] { Camera("bad name", 1024, 768, k, {}, I, t); }).find("invalid name"),
            std::string::npos);
  EXPECT_NE(message([&] {
              Camera("c1", 1024, 768, k, {std::nan(""), 0, 0, 0, 0}, I, t);
            }).find("distortion coefficients must be finite"),
            std::string::npos);
}

TEST(Camera, InImageUsesPixelCentreConvention) {
  const Camera camera("c", 4, 3, {10, 10, 1.5, 1, 0}, {}, Eigen::Matrix3d::Identity(),
                      Eigen::Vector3d::Zero());
  EXPECT_TRUE(camera.inImage({-0.5, -0.5}));
  EXPECT_TRUE(camera.inImage({3.49, 2.49}));
  EXPECT_FALSE(camera.inImage({3.5, 1}));
  EXPECT_FALSE(camera.inImage({1, -0.51}));
}

}  // namespace
}  // namespace lumistage
