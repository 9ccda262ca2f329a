#include "core/body/joint_pose_fit.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <stdexcept>

namespace lumistage {

namespace {

// The fitted quantities as one vector: [scale, root translation (3), root rotation vector (3),
// then the free Euler angles of every other joint].
struct Parameterisation {
  struct Angle {
    int joint, axis;
    double lower, upper;
  };
  std::vector<Angle> angles;
  int size() const { return 7 + static_cast<int>(angles.size()); }

  explicit Parameterisation(const Skeleton& skeleton) {
    for (int j = 1; j < skeleton.jointCount(); ++j) {
      const JointLimits& l = skeleton.joint(j).limits;
      for (int a = 0; a < 3; ++a) {
        if (l.upper_rad[a] > l.lower_rad[a])
          angles.push_back({j, a, l.lower_rad[a], l.upper_rad[a]});
      }
    }
  }
  Eigen::VectorXd pack(const JointPoseFit& fit) const {
    Eigen::VectorXd x(size());
    x[0] = fit.scale;
    x.segment<3>(1) = fit.pose.root_translation_m;
    x.segment<3>(4) = fit.pose.angles_rad[0];
    for (size_t i = 0; i < angles.size(); ++i)
      x[7 + i] = fit.pose.angles_rad[angles[i].joint][angles[i].axis];
    return x;
  }
  void unpack(const Eigen::VectorXd& x, JointPoseFit& fit) const {
    fit.scale = x[0];
    fit.pose.root_translation_m = x.segment<3>(1);
    fit.pose.angles_rad[0] = x.segment<3>(4);
    for (size_t i = 0; i < angles.size(); ++i)
      fit.pose.angles_rad[angles[i].joint][angles[i].axis] = x[7 + i];
  }
  void clamp(Eigen::VectorXd& x) const {
    x[0] = std::clamp(x[0], 0.5, 2.0);
    for (size_t i = 0; i < angles.size(); ++i)
      x[7 + i] = std::clamp(x[7 + i], angles[i].lower, angles[i].upper);
  }
};

}  // namespace

JointPoseFit initialJointPoseFit(const Skeleton& skeleton,
                                 const std::vector<Eigen::Vector3d>& targets) {
  if (static_cast<int>(targets.size()) != skeleton.jointCount())
    throw std::invalid_argument("joint pose fit: expected one target a joint");
  JointPoseFit fit;
  fit.pose = Pose::rest(skeleton.jointCount());
  const std::vector<Eigen::Vector3d>& rest = skeleton.restPositions();
  // Scale: the targets' mean distance from their centroid over the rest skeleton's.
  Eigen::Vector3d ct = Eigen::Vector3d::Zero(), cr = Eigen::Vector3d::Zero();
  for (size_t j = 0; j < targets.size(); ++j) ct += targets[j], cr += rest[j];
  ct /= double(targets.size()), cr /= double(targets.size());
  double dt = 0, dr = 0;
  for (size_t j = 0; j < targets.size(); ++j)
    dt += (targets[j] - ct).norm(), dr += (rest[j] - cr).norm();
  fit.scale = dr > 0 ? std::clamp(dt / dr, 0.5, 2.0) : 1.0;
  fit.pose.root_translation_m = targets[0] / fit.scale - rest[0];
  return fit;
}

JointPoseFit fitPoseToJoints(const Skeleton& skeleton, const std::vector<Eigen::Vector3d>& targets,
                             const JointPoseFit& initial, const JointPoseFitOptions& options) {
  const int joints = skeleton.jointCount();
  if (static_cast<int>(targets.size()) != joints)
    throw std::invalid_argument("joint pose fit: expected one target a joint");
  // The matrices stay with the thread, for a studio that fits every frame.
  thread_local struct Workspace {
    std::vector<Eigen::Vector3d> positions;
    Eigen::VectorXd x, x0, r, r_try, x_try, g;
    Eigen::MatrixXd J, JtJ, A;
    Eigen::LDLT<Eigen::MatrixXd> ldlt;
  } w;
  const Parameterisation param(skeleton);
  const int n = param.size();
  const int m = 3 * joints + static_cast<int>(param.angles.size());
  JointPoseFit fit = initial;
  if (static_cast<int>(fit.pose.angles_rad.size()) != joints) fit.pose = Pose::rest(joints);
  Eigen::VectorXd& x = w.x;
  x = param.pack(fit);
  param.clamp(x);
  w.x0 = x;
  if (options.prior_at_rest) w.x0.tail(param.angles.size()).setZero();

  JointPoseFit work = fit;
  auto residuals = [&](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
    param.unpack(p, work);
    skeleton.jointPositions(work.pose, w.positions);
    r.resize(m);
    for (int j = 0; j < joints; ++j) r.segment<3>(3 * j) = p[0] * w.positions[j] - targets[j];
    for (size_t i = 0; i < param.angles.size(); ++i)
      r[3 * joints + i] = options.angle_prior * (p[7 + i] - w.x0[7 + i]);
  };

  Eigen::VectorXd &r = w.r, &r_try = w.r_try, &x_try = w.x_try;
  w.J.resize(m, n);
  residuals(x, r);
  double cost = r.squaredNorm(), lambda = 1e-3;
  int it = 0;
  for (; it < options.max_iterations; ++it) {
    // Forward differences: the problem is small (about 70 parameters, 24 joints).
    for (int k = 0; k < n; ++k) {
      if (k == 0 && !options.fit_scale) {
        w.J.col(0).setZero();
        continue;
      }
      const double h = 1e-6;
      x_try = x;
      x_try[k] += h;
      residuals(x_try, r_try);
      w.J.col(k) = (r_try - r) / h;
    }
    w.JtJ.noalias() = w.J.transpose() * w.J;
    w.g.noalias() = w.J.transpose() * r;
    bool improved = false;
    for (int tries = 0; tries < 10 && !improved; ++tries) {
      w.A = w.JtJ;
      w.A.diagonal() += lambda * (w.JtJ.diagonal().array() + 1e-9).matrix();
      w.ldlt.compute(w.A);
      x_try = x - w.ldlt.solve(w.g);
      param.clamp(x_try);
      if (!options.fit_scale) x_try[0] = x[0];
      residuals(x_try, r_try);
      const double c = r_try.squaredNorm();
      if (c < cost) {
        improved = true;
        const double gain = cost - c;
        x.swap(x_try);
        r.swap(r_try);
        cost = c;
        lambda = std::max(lambda / 3, 1e-9);
        if (gain < 1e-12) it = options.max_iterations;
      } else {
        lambda *= 4;
      }
    }
    if (!improved) break;
  }
  param.unpack(x, fit);
  skeleton.jointPositions(fit.pose, w.positions);
  double sum = 0;
  for (int j = 0; j < joints; ++j) sum += (fit.scale * w.positions[j] - targets[j]).squaredNorm();
  fit.rms_m = std::sqrt(sum / joints);
  fit.iterations = it;
  return fit;
}

}  // namespace lumistage

#include "core/body/skinned_mesh.h"

namespace lumistage {

void posedScaledMesh(const SkinnedMesh& mesh, const JointPoseFit& fit, Eigen::Matrix3Xf& positions,
                     Eigen::Matrix3Xf& normals) {
  thread_local std::vector<Eigen::Affine3f> transforms;
  mesh.skeleton.skinningTransforms(fit.pose, transforms);
  skinMesh(mesh, transforms, positions, normals);
  positions *= static_cast<float>(fit.scale);
}

}  // namespace lumistage
