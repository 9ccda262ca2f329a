#include "core/calib/bundle_adjuster.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <cmath>

namespace lumistage {

namespace {

struct ReprojectionError {
  Eigen::Vector2d observed;

  template <typename T>
  bool operator()(const T* rotation, const T* translation, const T* intrinsics, const T* point,
                  T* residual) const {
    T p[3];
    ceres::AngleAxisRotatePoint(rotation, point, p);
    p[0] += translation[0], p[1] += translation[1], p[2] += translation[2];
    if (p[2] <= T(1e-9)) {  // behind the camera: a large, constant residual
      residual[0] = residual[1] = T(1e3);
      return true;
    }
    const T x = p[0] / p[2], y = p[1] / p[2];
    const T r2 = x * x + y * y;
    const T radial = T(1) + r2 * (intrinsics[3] + r2 * intrinsics[4]);
    residual[0] = intrinsics[0] * x * radial + intrinsics[1] - T(observed.x());
    residual[1] = intrinsics[0] * y * radial + intrinsics[2] - T(observed.y());
    return true;
  }
};

double rmsOf(const std::vector<BundleCamera>& cameras, const std::vector<Eigen::Vector3d>& points,
             const std::vector<BundleObservation>& observations) {
  double sum = 0;
  for (const BundleObservation& o : observations) {
    Eigen::Vector2d pixel;
    sum += projectBundle(cameras[o.camera], points[o.point], pixel)
               ? (pixel - o.pixel).squaredNorm()
               : 2e6;
  }
  return observations.empty() ? 0 : std::sqrt(sum / observations.size());
}

}  // namespace

bool projectBundle(const BundleCamera& c, const Eigen::Vector3d& point, Eigen::Vector2d& pixel) {
  double p[3];
  ceres::AngleAxisRotatePoint(c.rotation.data(), point.data(), p);
  p[0] += c.translation[0], p[1] += c.translation[1], p[2] += c.translation[2];
  if (p[2] <= 1e-9) return false;
  const double x = p[0] / p[2], y = p[1] / p[2], r2 = x * x + y * y;
  const double radial = 1 + r2 * (c.k1 + r2 * c.k2);
  pixel = {c.focal_px * x * radial + c.cx, c.focal_px * y * radial + c.cy};
  return true;
}

BundleResult adjustBundle(std::vector<BundleCamera>& cameras, std::vector<Eigen::Vector3d>& points,
                          const std::vector<BundleObservation>& observations,
                          const BundleOptions& options) {
  BundleResult result;
  result.initial_rms_px = rmsOf(cameras, points, observations);
  std::vector<std::array<double, 5>> intrinsics(cameras.size());
  for (size_t c = 0; c < cameras.size(); ++c) {
    const BundleCamera& k = cameras[c];
    intrinsics[c] = {k.focal_px, k.cx, k.cy, k.k1, k.k2};
  }
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  std::vector<uint8_t> used(cameras.size(), 0);
  for (const BundleObservation& o : observations) {
    auto* cost = new ceres::AutoDiffCostFunction<ReprojectionError, 2, 3, 3, 5, 3>(
        new ReprojectionError{o.pixel});
    ceres::LossFunction* loss =
        options.huber_px > 0 ? new ceres::HuberLoss(options.huber_px) : nullptr;
    BundleCamera& c = cameras[o.camera];
    problem.AddResidualBlock(cost, loss, c.rotation.data(), c.translation.data(),
                             intrinsics[o.camera].data(), points[o.point].data());
    used[o.camera] = 1;
  }
  for (size_t c = 0; c < cameras.size(); ++c) {
    if (!used[c]) continue;
    double* k = intrinsics[c].data();
    if (!options.refine_intrinsics) {
      problem.SetParameterBlockConstant(k);
    } else if (!options.refine_distortion || !options.refine_principal_point) {
      std::vector<int> constant;
      for (int i = 1; i < 5; ++i) {
        if ((i < 3 && !options.refine_principal_point) || (i >= 3 && !options.refine_distortion))
          constant.push_back(i);
      }
      problem.SetManifold(k, new ceres::SubsetManifold(5, constant));
    }
    if (static_cast<int>(c) == options.fixed_camera) {
      problem.SetParameterBlockConstant(cameras[c].rotation.data());
      problem.SetParameterBlockConstant(cameras[c].translation.data());
    } else if (static_cast<int>(c) == options.scale_camera) {
      problem.SetManifold(cameras[c].translation.data(), new ceres::SphereManifold<3>());
    }
  }
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_SCHUR;
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = 2;
  solver.function_tolerance = 1e-10;
  solver.parameter_tolerance = 1e-10;
  solver.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  for (size_t c = 0; c < cameras.size(); ++c) {
    BundleCamera& k = cameras[c];
    k.focal_px = intrinsics[c][0], k.cx = intrinsics[c][1], k.cy = intrinsics[c][2];
    k.k1 = intrinsics[c][3], k.k2 = intrinsics[c][4];
  }
  result.final_rms_px = rmsOf(cameras, points, observations);
  result.iterations = static_cast<int>(summary.iterations.size());
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  return result;
}

}  // namespace lumistage
