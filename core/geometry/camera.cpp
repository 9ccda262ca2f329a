#include "core/geometry/camera.h"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>

namespace lumistage {

Eigen::Matrix3d Intrinsics::matrix() const {
  Eigen::Matrix3d K;
  K << fx, skew, cx, 0, fy, cy, 0, 0, 1;
  return K;
}

Intrinsics Intrinsics::fromMatrix(const Eigen::Matrix3d& K) {
  const Eigen::Matrix3d k = K / K(2, 2);
  return {k(0, 0), k(1, 1), k(0, 2), k(1, 2), k(0, 1)};
}

Eigen::Vector2d Distortion::apply(const Eigen::Vector2d& undistorted) const {
  Eigen::Vector2d d;
  apply(undistorted.x(), undistorted.y(), d.x(), d.y());
  return d;
}

std::optional<Eigen::Vector2d> Distortion::remove(const Eigen::Vector2d& distorted) const {
  if (isZero()) return distorted;
  // Newton on f(x) = apply(x) - distorted, from x = distorted; the Jacobian is analytic. Converges
  // in a handful of steps for real lenses; a non-positive Jacobian determinant means we left the
  // monotonic part of the polynomial.
  Eigen::Vector2d x = distorted;
  for (int iteration = 0; iteration < 50; ++iteration) {
    const double u = x.x(), v = x.y();
    const double r2 = u * u + v * v;
    const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double dradial_dr2 = k1 + r2 * (2 * k2 + 3 * k3 * r2);
    Eigen::Matrix2d J;
    J(0, 0) = radial + 2 * u * u * dradial_dr2 + 2 * p1 * v + 6 * p2 * u;
    J(0, 1) = 2 * u * v * dradial_dr2 + 2 * p1 * u + 2 * p2 * v;
    J(1, 0) = 2 * u * v * dradial_dr2 + 2 * p1 * u + 2 * p2 * v;
    J(1, 1) = radial + 2 * v * v * dradial_dr2 + 6 * p1 * v + 2 * p2 * u;
    const double det = J.determinant();
    if (!(det > 1e-12)) return std::nullopt;
    const Eigen::Vector2d residual = apply(x) - distorted;
    const Eigen::Vector2d step = J.inverse() * residual;
    x -= step;
    if (!x.allFinite()) return std::nullopt;
    if (step.squaredNorm() < 1e-30) break;
  }
  if ((apply(x) - distorted).norm() > 1e-10 * (1 + distorted.norm())) return std::nullopt;
  return x;
}

namespace {

void require(bool ok, const std::string& camera, const std::string& what) {
  if (!ok) throw std::invalid_argument("camera '" + camera + "': " + what);
}

}  // namespace

Camera::Camera(std::string name, int width, int height, const Intrinsics& intrinsics,
               const Distortion& distortion, const Eigen::Matrix3d& R, const Eigen::Vector3d& t)
    : name_(std::move(name)),
      width_(width),
      height_(height),
      intrinsics_(intrinsics),
      distortion_(distortion),
      R_(R),
      t_(t) {
  require(isValidName(name_), name_,
          "invalid name: expected 1-64 characters of A-Z a-z 0-9 _ . - (not starting with . or -)");
  require(
      width_ > 0 && height_ > 0, name_,
      "image size must be positive, got " + std::to_string(width_) + "x" + std::to_string(height_));
  const auto& k = intrinsics_;
  require(std::isfinite(k.fx) && k.fx > 0, name_,
          "focal length fx must be a positive number, got " + std::to_string(k.fx));
  require(std::isfinite(k.fy) && k.fy > 0, name_,
          "focal length fy must be a positive number, got " + std::to_string(k.fy));
  require(std::isfinite(k.cx) && std::isfinite(k.cy) && std::isfinite(k.skew), name_,
          "principal point and skew must be finite numbers");
  const auto& d = distortion_;
  require(std::isfinite(d.k1) && std::isfinite(d.k2) && std::isfinite(d.p1) &&
              std::isfinite(d.p2) && std::isfinite(d.k3),
          name_, "distortion coefficients must be finite numbers");
  require(R_.allFinite() && t_.allFinite(), name_, "rotation and translation must be finite");
  const double orthonormality = (R_.transpose() * R_ - Eigen::Matrix3d::Identity()).norm();
  require(orthonormality < 1e-6, name_,
          "rotation is not orthonormal (|R^T R - I| = " + std::to_string(orthonormality) +
              ", expected < 1e-6)");
  require(R_.determinant() > 0, name_,
          "rotation has determinant " + std::to_string(R_.determinant()) +
              ", expected +1 (a reflection, not a rotation)");
}

Eigen::Matrix<double, 3, 4> Camera::projectionMatrix() const {
  Eigen::Matrix<double, 3, 4> Rt;
  Rt << R_, t_;
  return intrinsics_.matrix() * Rt;
}

std::optional<Eigen::Vector2d> Camera::project(const Eigen::Vector3d& world) const {
  const Eigen::Vector3d c = toCamera(world);
  if (!(c.z() > 0)) return std::nullopt;
  return normalizedToPixel(distortion_.apply(Eigen::Vector2d(c.x() / c.z(), c.y() / c.z())));
}

template <typename Scalar>
void Camera::project(const Eigen::Matrix<Scalar, 3, Eigen::Dynamic>& world,
                     Eigen::Matrix<Scalar, 2, Eigen::Dynamic>& pixels,
                     Eigen::Matrix<Scalar, Eigen::Dynamic, 1>& depths) const {
  const Eigen::Index n = world.cols();
  if (pixels.cols() != n) pixels.resize(2, n);
  if (depths.size() != n) depths.resize(n);
  const Eigen::Matrix<Scalar, 3, 3> R = R_.cast<Scalar>();
  const Eigen::Matrix<Scalar, 3, 1> t = t_.cast<Scalar>();
  const Scalar fx = Scalar(intrinsics_.fx), fy = Scalar(intrinsics_.fy);
  const Scalar cx = Scalar(intrinsics_.cx), cy = Scalar(intrinsics_.cy);
  const Scalar skew = Scalar(intrinsics_.skew);
  const bool distorted = !distortion_.isZero();
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Matrix<Scalar, 3, 1> c = R * world.col(i) + t;
    const Scalar inv_z = Scalar(1) / c.z();
    Scalar x = c.x() * inv_z, y = c.y() * inv_z;
    if (distorted) distortion_.apply(Scalar(x), Scalar(y), x, y);
    pixels(0, i) = fx * x + skew * y + cx;
    pixels(1, i) = fy * y + cy;
    depths(i) = c.z();
  }
}

template void Camera::project<float>(const Eigen::Matrix<float, 3, Eigen::Dynamic>&,
                                     Eigen::Matrix<float, 2, Eigen::Dynamic>&,
                                     Eigen::Matrix<float, Eigen::Dynamic, 1>&) const;
template void Camera::project<double>(const Eigen::Matrix<double, 3, Eigen::Dynamic>&,
                                      Eigen::Matrix<double, 2, Eigen::Dynamic>&,
                                      Eigen::Matrix<double, Eigen::Dynamic, 1>&) const;

std::optional<Ray> Camera::unproject(const Eigen::Vector2d& pixel) const {
  const std::optional<Eigen::Vector2d> x = distortion_.remove(pixelToNormalized(pixel));
  if (!x) return std::nullopt;
  const Eigen::Vector3d direction_cam(x->x(), x->y(), 1.0);
  return Ray{centre(), (R_.transpose() * direction_cam).normalized()};
}

Eigen::Vector2d Camera::distortPixel(const Eigen::Vector2d& undistorted_pixel) const {
  return normalizedToPixel(distortion_.apply(pixelToNormalized(undistorted_pixel)));
}

std::optional<Eigen::Vector2d> Camera::undistortPixel(
    const Eigen::Vector2d& distorted_pixel) const {
  const std::optional<Eigen::Vector2d> x = distortion_.remove(pixelToNormalized(distorted_pixel));
  if (!x) return std::nullopt;
  return normalizedToPixel(*x);
}

Eigen::Vector2d Camera::pixelToNormalized(const Eigen::Vector2d& pixel) const {
  const double y = (pixel.y() - intrinsics_.cy) / intrinsics_.fy;
  const double x = (pixel.x() - intrinsics_.cx - intrinsics_.skew * y) / intrinsics_.fx;
  return {x, y};
}

Eigen::Vector2d Camera::normalizedToPixel(const Eigen::Vector2d& normalized) const {
  return {intrinsics_.fx * normalized.x() + intrinsics_.skew * normalized.y() + intrinsics_.cx,
          intrinsics_.fy * normalized.y() + intrinsics_.cy};
}

bool Camera::inImage(const Eigen::Vector2d& pixel) const {
  return pixel.x() >= -0.5 && pixel.y() >= -0.5 && pixel.x() < width_ - 0.5 &&
         pixel.y() < height_ - 0.5;
}

}  // namespace lumistage
