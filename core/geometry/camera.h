#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>

#include "core/base/names.h"  // isValidName: camera and node names

namespace lumistage {

// Pinhole intrinsics in pixels. Pixel (0, 0) is the centre of the top-left pixel (OpenCV's
// convention); K = [fx skew cx; 0 fy cy; 0 0 1].
struct Intrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0, skew = 0;

  Eigen::Matrix3d matrix() const;
  static Intrinsics fromMatrix(const Eigen::Matrix3d& K);  // K normalised so that K(2,2) = 1
  bool operator==(const Intrinsics&) const = default;
};

// OpenCV's radial-tangential lens model (k1, k2, p1, p2, k3) on normalised image coordinates:
//   r² = x² + y², radial = 1 + k1 r² + k2 r⁴ + k3 r⁶
//   xd = x·radial + 2 p1 x y + p2 (r² + 2x²),  yd = y·radial + p1 (r² + 2y²) + 2 p2 x y
struct Distortion {
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;

  bool isZero() const { return k1 == 0 && k2 == 0 && p1 == 0 && p2 == 0 && k3 == 0; }
  template <typename T>
  void apply(T x, T y, T& xd, T& yd) const;
  Eigen::Vector2d apply(const Eigen::Vector2d& undistorted) const;
  // The inverse, by Newton's method. Empty where it does not converge: far outside the field in
  // which the polynomial is monotonic, i.e. outside any real lens's image.
  std::optional<Eigen::Vector2d> remove(const Eigen::Vector2d& distorted) const;
  bool operator==(const Distortion&) const = default;
};

struct Ray {
  Eigen::Vector3d origin;
  Eigen::Vector3d direction;  // unit length
};

// A calibrated camera of the rig. World frame: metres, z up, the stage floor at z = 0. Camera
// frame: OpenCV's (x right, y down, z forward); x_cam = R·x_world + t.
class Camera {
 public:
  Camera() = default;
  // Throws std::invalid_argument, naming the camera and the parameter, when a value is out of
  // range: empty or unsafe name, non-positive size or focal length, non-finite numbers, or an R
  // that is not a rotation (orthonormal within 1e-6, determinant +1).
  Camera(std::string name, int width, int height, const Intrinsics& intrinsics,
         const Distortion& distortion, const Eigen::Matrix3d& R, const Eigen::Vector3d& t);

  const std::string& name() const { return name_; }
  const std::string& node() const { return node_; }  // set by the Rig that owns the camera
  void setNode(std::string node) { node_ = std::move(node); }
  int width() const { return width_; }
  int height() const { return height_; }
  const Intrinsics& intrinsics() const { return intrinsics_; }
  const Distortion& distortion() const { return distortion_; }
  const Eigen::Matrix3d& rotation() const { return R_; }
  const Eigen::Vector3d& translation() const { return t_; }

  Eigen::Vector3d centre() const { return -R_.transpose() * t_; }
  Eigen::Vector3d viewingDirection() const { return R_.row(2).transpose(); }
  Eigen::Matrix<double, 3, 4> projectionMatrix() const;  // K[R|t], lens distortion left out

  Eigen::Vector3d toCamera(const Eigen::Vector3d& world) const { return R_ * world + t_; }
  // Pixel of a world point, lens distortion included; empty for a point on or behind the camera
  // plane.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& world) const;
  // Batch projection (the refinement projects ~500k points a frame). Writes pixels and depths
  // along the optical axis; a depth <= 0 marks a point behind the camera, whose pixel is
  // meaningless. Outputs are resized only when their size differs: reuse them and the call does
  // not allocate.
  template <typename Scalar>
  void project(const Eigen::Matrix<Scalar, 3, Eigen::Dynamic>& world,
               Eigen::Matrix<Scalar, 2, Eigen::Dynamic>& pixels,
               Eigen::Matrix<Scalar, Eigen::Dynamic, 1>& depths) const;

  // The ray from the camera centre through a (distorted) pixel; empty where undistortion fails.
  std::optional<Ray> unproject(const Eigen::Vector2d& pixel) const;

  // Between distorted pixels (what the sensor sees) and ideal pinhole pixels.
  Eigen::Vector2d distortPixel(const Eigen::Vector2d& undistorted_pixel) const;
  std::optional<Eigen::Vector2d> undistortPixel(const Eigen::Vector2d& distorted_pixel) const;

  // Between pixels and normalised image coordinates (no distortion involved).
  Eigen::Vector2d pixelToNormalized(const Eigen::Vector2d& pixel) const;
  Eigen::Vector2d normalizedToPixel(const Eigen::Vector2d& normalized) const;

  // Whether a pixel lies on the image: [-0.5, width - 0.5) x [-0.5, height - 0.5).
  bool inImage(const Eigen::Vector2d& pixel) const;

  bool operator==(const Camera&) const = default;

 private:
  std::string name_;
  std::string node_;
  int width_ = 0, height_ = 0;
  Intrinsics intrinsics_;
  Distortion distortion_;
  Eigen::Matrix3d R_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t_ = Eigen::Vector3d::Zero();
};

template <typename T>
void Distortion::apply(T x, T y, T& xd, T& yd) const {
  const T r2 = x * x + y * y;
  const T radial = T(1) + r2 * (T(k1) + r2 * (T(k2) + r2 * T(k3)));
  const T xy2 = T(2) * x * y;
  xd = x * radial + T(p1) * xy2 + T(p2) * (r2 + T(2) * x * x);
  yd = y * radial + T(p1) * (r2 + T(2) * y * y) + T(p2) * xy2;
}

}  // namespace lumistage
