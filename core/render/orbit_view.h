#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/geometry/camera.h"
#include "core/net/message_types.h"

namespace lumistage {

// Where a virtual camera is and where it looks: its centre, its orientation (world to camera,
// OpenCV axes: x right, y down, z forward) and its vertical field of view. What a camera path
// interpolates.
struct ViewPose {
  Eigen::Vector3d eye = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // world -> camera
  double fov_y_rad = 0.8;
  // A pinhole camera of this pose (no distortion, principal point at the centre).
  Camera camera(int width, int height, const std::string& name = "view") const;
};

// The director's virtual camera: orbits a target point on a sphere, z up, never rolls. Drag to
// orbit (yaw about the vertical through the target, pitch up and down), pan (the target moves in
// the view's plane), zoom (the distance to the target). Snapping to an input camera takes that
// camera's centre, viewing direction and field of view.
class OrbitView {
 public:
  static constexpr double kMinDistance_m = 0.3, kMaxDistance_m = 40.0;
  static constexpr double kMaxPitch_rad = 1.55;  // just short of straight down or up

  OrbitView() = default;
  // From the front-left of the stage, 4.6 m out and 1.7 m up, looking at the stage centre 1 m up.
  static OrbitView studioDefault();
  // The view through an input camera: its centre and viewing direction (its roll is dropped), its
  // vertical field of view; the target is on its axis where it passes closest to the stage's
  // vertical axis (x = y = 0), at least 0.5 m out.
  static OrbitView fromCamera(const Camera& camera);
  static OrbitView fromPose(const ViewPose& pose, double distance_m);

  const Eigen::Vector3d& target() const { return target_; }
  double yaw() const { return yaw_rad_; }
  double pitch() const { return pitch_rad_; }
  double distance() const { return distance_m_; }
  double fovY() const { return fov_y_rad_; }
  void setTarget(const Eigen::Vector3d& target) { target_ = target; }
  void set(double yaw_rad, double pitch_rad, double distance_m);

  Eigen::Vector3d eye() const;
  ViewPose pose() const;
  Camera camera(int width, int height) const { return pose().camera(width, height); }

  // Turns the eye about the target: yaw about the vertical, pitch clamped to +-kMaxPitch_rad.
  void orbit(double yaw_rad, double pitch_rad);
  // Moves the target (and the eye with it) in the view plane: right and up, metres.
  void pan(double right_m, double up_m);
  // Multiplies the distance to the target (below 1: closer), clamped.
  void zoom(double factor);
  // For a drag of (dx, dy) pixels in a viewport of the given height: orbit, pan or zoom by the
  // amount a user expects (a full-height drag orbits ~180 degrees; a pan follows the cursor at the
  // target's depth).
  void dragOrbit(double dx_px, double dy_px, int viewport_height);
  void dragPan(double dx_px, double dy_px, int viewport_height);
  void wheelZoom(double steps);  // one step (a mouse wheel notch): 10 %

 private:
  Eigen::Vector3d target_{0, 0, 1.0};
  double yaw_rad_ = 0, pitch_rad_ = 0.2, distance_m_ = 4.6, fov_y_rad_ = 0.8;
};

// The message the nodes render for: the pose as a pinhole ViewData of width x height.
ViewData toViewData(const ViewPose& pose, int width, int height, int view_id = 0);

}  // namespace lumistage
