#include "core/geometry/projection_matrix.h"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <string>

namespace lumistage {

DecomposedProjection decomposeProjection(const Eigen::Matrix<double, 3, 4>& P_in) {
  if (!P_in.allFinite()) throw std::invalid_argument("projection matrix has non-finite entries");
  // Fix the overall sign first so that det(M) > 0: then the RQ factor R with a positive-diagonal K
  // is a rotation, not a reflection.
  Eigen::Matrix<double, 3, 4> P = P_in;
  Eigen::Matrix3d M = P.leftCols<3>();
  const double det = M.determinant();
  const double scale = M.norm();
  if (!(std::abs(det) > 1e-12 * scale * scale * scale)) {
    throw std::invalid_argument("projection matrix is singular (det of its left 3x3 block is " +
                                std::to_string(det) + "); expected a finite camera");
  }
  if (det < 0) {
    P = -P;
    M = -M;
  }

  // RQ through QR: with J the exchange matrix, (J M)^T = Q U gives M = (J U^T J)(J Q^T), where
  // J U^T J is upper triangular and J Q^T orthonormal.
  Eigen::Matrix3d J = Eigen::Matrix3d::Zero();
  J(0, 2) = J(1, 1) = J(2, 0) = 1;
  const Eigen::HouseholderQR<Eigen::Matrix3d> qr((J * M).transpose());
  const Eigen::Matrix3d Q = qr.householderQ();
  const Eigen::Matrix3d U = qr.matrixQR().triangularView<Eigen::Upper>();
  Eigen::Matrix3d K = J * U.transpose() * J;
  Eigen::Matrix3d R = J * Q.transpose();
  // Make K's diagonal positive; D·D = I leaves the product unchanged.
  const Eigen::Vector3d signs = K.diagonal().array().sign();
  K = K * signs.asDiagonal();
  R = signs.asDiagonal() * R;

  DecomposedProjection out;
  out.t = K.inverse() * P.col(3);
  out.K = K / K(2, 2);
  out.R = R;
  return out;
}

}  // namespace lumistage
