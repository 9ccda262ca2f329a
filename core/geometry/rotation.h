#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace lumistage {

// A rotation vector (axis times angle, radians; OpenCV's Rodrigues vector, the root's rotation of
// a Pose) as a matrix, and back.
inline Eigen::Matrix3d rotationFromVector(const Eigen::Vector3d& v) {
  const double angle = v.norm();
  return angle > 0 ? Eigen::AngleAxisd(angle, v / angle).toRotationMatrix()
                   : Eigen::Matrix3d::Identity();
}

inline Eigen::Vector3d rotationVectorOf(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.angle() * aa.axis();
}

}  // namespace lumistage
