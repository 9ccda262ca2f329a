#pragma once

#include <Eigen/Core>

namespace lumistage {

struct DecomposedProjection {
  Eigen::Matrix3d K;  // upper triangular, positive diagonal, K(2,2) = 1
  Eigen::Matrix3d R;  // rotation, world to camera
  Eigen::Vector3d t;  // x_cam = R·x_world + t
};

// Splits a 3x4 projection matrix P ~ K[R|t] (any non-zero scale, either sign) into K, R and t, by
// an RQ decomposition of its left 3x3 block. Throws std::invalid_argument when that block is
// singular (P maps no finite camera centre) or the matrix is not finite.
DecomposedProjection decomposeProjection(const Eigen::Matrix<double, 3, 4>& P);

}  // namespace lumistage
