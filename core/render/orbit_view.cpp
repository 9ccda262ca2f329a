#include "core/render/orbit_view.h"

#include <algorithm>
#include <cmath>

namespace lumistage {

namespace {

// World-to-camera rotation of a camera at `eye` looking along `forward`, z up, no roll.
Eigen::Matrix3d lookRotation(const Eigen::Vector3d& forward) {
  const Eigen::Vector3d z = forward.normalized();
  Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ());
  if (x.norm() < 1e-9) x = Eigen::Vector3d::UnitX();  // straight down or up
  x.normalize();
  Eigen::Matrix3d R;
  R.row(0) = x;
  R.row(1) = z.cross(x);
  R.row(2) = z;
  return R;
}

}  // namespace

Camera ViewPose::camera(int width, int height, const std::string& name) const {
  Intrinsics k;
  k.fy = 0.5 * height / std::tan(0.5 * fov_y_rad);
  k.fx = k.fy;
  k.cx = 0.5 * (width - 1);
  k.cy = 0.5 * (height - 1);
  const Eigen::Matrix3d R = orientation.normalized().toRotationMatrix();
  return Camera(name, width, height, k, Distortion{}, R, -R * eye);
}

OrbitView OrbitView::studioDefault() {
  OrbitView v;
  const Eigen::Vector3d eye(-3.2, -3.2, 1.7);
  v.target_ = Eigen::Vector3d(0, 0, 1.0);
  const Eigen::Vector3d d = eye - v.target_;
  v.distance_m_ = d.norm();
  v.yaw_rad_ = std::atan2(d.y(), d.x());
  v.pitch_rad_ = std::asin(d.z() / v.distance_m_);
  return v;
}

OrbitView OrbitView::fromPose(const ViewPose& pose, double distance_m) {
  OrbitView v;
  const Eigen::Vector3d forward =
      pose.orientation.normalized().toRotationMatrix().row(2).transpose();
  v.distance_m_ = std::clamp(distance_m, kMinDistance_m, kMaxDistance_m);
  v.target_ = pose.eye + forward * v.distance_m_;
  const Eigen::Vector3d back = -forward;
  v.yaw_rad_ = std::atan2(back.y(), back.x());
  v.pitch_rad_ =
      std::clamp(std::asin(std::clamp(back.z(), -1.0, 1.0)), -kMaxPitch_rad, kMaxPitch_rad);
  v.fov_y_rad_ = pose.fov_y_rad;
  return v;
}

OrbitView OrbitView::fromCamera(const Camera& camera) {
  const Eigen::Vector3d c = camera.centre(), d = camera.viewingDirection();
  // Closest approach of the axis c + s d to the vertical line x = y = 0.
  const Eigen::Vector2d c2 = c.head<2>(), d2 = d.head<2>();
  double s = d2.squaredNorm() > 1e-9 ? -c2.dot(d2) / d2.squaredNorm() : 4.0;
  s = std::max(s, 0.5);
  ViewPose pose;
  pose.eye = c;
  pose.orientation = Eigen::Quaterniond(lookRotation(d));
  pose.fov_y_rad = 2 * std::atan(0.5 * camera.height() / camera.intrinsics().fy);
  return fromPose(pose, s);
}

void OrbitView::set(double yaw_rad, double pitch_rad, double distance_m) {
  yaw_rad_ = yaw_rad;
  pitch_rad_ = std::clamp(pitch_rad, -kMaxPitch_rad, kMaxPitch_rad);
  distance_m_ = std::clamp(distance_m, kMinDistance_m, kMaxDistance_m);
}

Eigen::Vector3d OrbitView::eye() const {
  const double cp = std::cos(pitch_rad_);
  return target_ + distance_m_ * Eigen::Vector3d(cp * std::cos(yaw_rad_), cp * std::sin(yaw_rad_),
                                                 std::sin(pitch_rad_));
}

ViewPose OrbitView::pose() const {
  ViewPose p;
  p.eye = eye();
  p.orientation = Eigen::Quaterniond(lookRotation(target_ - p.eye));
  p.fov_y_rad = fov_y_rad_;
  return p;
}

void OrbitView::orbit(double yaw_rad, double pitch_rad) {
  yaw_rad_ = std::remainder(yaw_rad_ + yaw_rad, 2 * M_PI);
  pitch_rad_ = std::clamp(pitch_rad_ + pitch_rad, -kMaxPitch_rad, kMaxPitch_rad);
}

void OrbitView::pan(double right_m, double up_m) {
  const Eigen::Matrix3d R = pose().orientation.toRotationMatrix();
  // Camera y points down: up is -y.
  target_ += right_m * R.row(0).transpose() - up_m * R.row(1).transpose();
}

void OrbitView::zoom(double factor) {
  distance_m_ = std::clamp(distance_m_ * factor, kMinDistance_m, kMaxDistance_m);
}

void OrbitView::dragOrbit(double dx_px, double dy_px, int viewport_height) {
  const double per_px = M_PI / std::max(1, viewport_height);
  // Dragging right turns the stage to the right: the eye goes left (decreasing yaw).
  orbit(-dx_px * per_px, dy_px * per_px);
}

void OrbitView::dragPan(double dx_px, double dy_px, int viewport_height) {
  // At the target's depth a pixel spans this many metres: the point under the cursor follows it.
  const double m_per_px =
      2 * distance_m_ * std::tan(0.5 * fov_y_rad_) / std::max(1, viewport_height);
  pan(-dx_px * m_per_px, dy_px * m_per_px);
}

void OrbitView::wheelZoom(double steps) {
  zoom(std::pow(0.9, steps));
}

ViewData toViewData(const ViewPose& pose, int width, int height, int view_id) {
  const Camera c = pose.camera(width, height);
  ViewData v;
  v.view = view_id;
  v.width = width;
  v.height = height;
  v.fx = float(c.intrinsics().fx);
  v.fy = float(c.intrinsics().fy);
  v.cx = float(c.intrinsics().cx);
  v.cy = float(c.intrinsics().cy);
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) v.rotation.push_back(float(c.rotation()(r, k)));
  }
  for (int k = 0; k < 3; ++k) v.translation.push_back(float(c.translation()[k]));
  return v;
}

}  // namespace lumistage
