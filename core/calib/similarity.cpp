#include "core/calib/similarity.h"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>

#include "core/base/error.h"

namespace lumistage {

Camera Similarity::apply(const Camera& c) const {
  // x_cam = R_c·X + t_c with X = Rᵀ(X' - t)/s; distances scale by s, so the camera-frame
  // coordinates do too: s·x_cam = R_c·Rᵀ·X' + s·t_c - R_c·Rᵀ·t.
  Eigen::Matrix3d R_new = c.rotation() * R.transpose();
  // Re-orthonormalise: the product of two rotations drifts by rounding only, but the Camera
  // checks to 1e-6 and a chain of these must not fail.
  R_new = Eigen::Quaterniond(R_new).normalized().toRotationMatrix();
  const Eigen::Vector3d t_new = scale * c.translation() - R_new * t;
  Camera out(c.name(), c.width(), c.height(), c.intrinsics(), c.distortion(), R_new, t_new);
  out.setNode(c.node());
  return out;
}

Rig Similarity::apply(const Rig& rig) const {
  std::vector<Camera> cameras;
  for (const Camera& c : rig.cameras()) cameras.push_back(apply(c));
  // A stage box of the old world is not one of the new: the caller decides (setStage).
  return Rig(std::move(cameras), rig.nodes());
}

bool nearlyOnALine(const std::vector<Eigen::Vector3d>& points, double ratio) {
  if (points.size() < 3) return true;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) mean += p;
  mean /= double(points.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : points) scatter += (p - mean) * (p - mean).transpose();
  // Eigenvalues ascending: the squares of the singular values.
  const Eigen::Vector3d e = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvalues();
  return !(std::sqrt(std::max(0.0, e[1])) > ratio * std::sqrt(std::max(0.0, e[2])));
}

Similarity alignPoints(const std::vector<Eigen::Vector3d>& from,
                       const std::vector<Eigen::Vector3d>& to, bool with_scale) {
  if (from.size() != to.size() || from.size() < 3)
    throw Error(fmt::format("alignment needs 3 or more point pairs, got {} and {}", from.size(),
                            to.size()));
  if (nearlyOnALine(from) || nearlyOnALine(to))
    throw Error(
        "alignment failed: the points lie (nearly) on a line, which leaves the rotation about it "
        "undetermined");
  Eigen::Matrix3Xd a(3, from.size()), b(3, to.size());
  for (size_t i = 0; i < from.size(); ++i) a.col(i) = from[i], b.col(i) = to[i];
  const Eigen::Matrix4d T = Eigen::umeyama(a, b, with_scale);
  Similarity s;
  s.scale = T.block<3, 3>(0, 0).col(0).norm();
  s.R = T.block<3, 3>(0, 0) / s.scale;
  s.t = T.block<3, 1>(0, 3);
  if (!std::isfinite(s.scale) || s.scale <= 0)
    throw Error("alignment failed: the points are degenerate (coincident or on a line)");
  return s;
}

double rotationAngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const double c = std::clamp(((a * b.transpose()).trace() - 1) / 2, -1.0, 1.0);
  return std::acos(c) * 180.0 / M_PI;
}

double intrinsicsDifferencePx(const Camera& estimate, const Camera& truth,
                              const std::vector<Eigen::Vector2d>& pixels) {
  double worst = 0;
  for (const Eigen::Vector2d& pixel : pixels) {
    const std::optional<Eigen::Vector2d> u = truth.undistortPixel(pixel);
    if (!u) continue;
    const Eigen::Vector2d n = truth.pixelToNormalized(*u);
    worst = std::max(worst, (estimate.distortPixel(estimate.normalizedToPixel(n)) - pixel).norm());
  }
  return worst;
}

double intrinsicsDifferencePx(const Camera& estimate, const Camera& truth) {
  std::vector<Eigen::Vector2d> grid;
  for (int gy = 0; gy <= 8; ++gy) {
    for (int gx = 0; gx <= 8; ++gx) {
      grid.emplace_back((0.05 + 0.1125 * gx) * truth.width(),
                        (0.05 + 0.1125 * gy) * truth.height());
    }
  }
  return intrinsicsDifferencePx(estimate, truth, grid);
}

RigComparison compareRigs(const Rig& estimate, const Rig& truth, bool align) {
  std::vector<Eigen::Vector3d> from, to;
  std::vector<std::pair<int, int>> matched;
  for (int i = 0; i < truth.cameraCount(); ++i) {
    const std::optional<int> e = estimate.findCamera(truth.camera(i).name());
    if (!e)
      throw Error(
          fmt::format("camera {} of the truth is not in the estimate", truth.camera(i).name()));
    matched.emplace_back(*e, i);
    from.push_back(estimate.camera(*e).centre());
    to.push_back(truth.camera(i).centre());
  }
  if (estimate.cameraCount() != truth.cameraCount())
    throw Error("the estimate has cameras that the truth does not");
  RigComparison out;
  if (align) out.alignment = alignPoints(from, to, true);
  double sum2 = 0;
  for (const auto& [e, i] : matched) {
    const Camera aligned = out.alignment.apply(estimate.camera(e));
    const Camera& t = truth.camera(i);
    CameraError err;
    err.name = t.name();
    err.centre_m = (aligned.centre() - t.centre()).norm();
    err.rotation_deg = rotationAngleDeg(aligned.rotation(), t.rotation());
    err.focal_rel = std::abs(aligned.intrinsics().fx - t.intrinsics().fx) / t.intrinsics().fx;
    out.max_centre_m = std::max(out.max_centre_m, err.centre_m);
    out.max_rotation_deg = std::max(out.max_rotation_deg, err.rotation_deg);
    out.max_focal_rel = std::max(out.max_focal_rel, err.focal_rel);
    err.intrinsics_px = intrinsicsDifferencePx(aligned, t);
    out.max_intrinsics_px = std::max(out.max_intrinsics_px, err.intrinsics_px);
    sum2 += err.centre_m * err.centre_m;
    out.cameras.push_back(err);
  }
  out.rms_centre_m = std::sqrt(sum2 / std::max<size_t>(1, matched.size()));
  return out;
}

}  // namespace lumistage
