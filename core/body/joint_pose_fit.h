#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/body/skeleton.h"

namespace lumistage {

// A skeleton pose fitted to 3D joint positions, with one bone-length scale: the posed skeleton's
// joints are scale x forwardKinematics(pose). Scaling the rest mesh by the same factor about the
// world origin keeps it bound (see posedScaledMesh).
struct JointPoseFit {
  Pose pose;
  double scale = 1.0;
  double rms_m = 0;  // root mean square joint distance after the fit
  int iterations = 0;
};

struct JointPoseFitOptions {
  int max_iterations = 30;
  bool fit_scale = true;
  // Pull of every joint angle toward the initial pose (metres of residual per radian): joint
  // positions leave the twist about a bone unobserved; this keeps it where it was.
  double angle_prior = 0.02;
  // Draw the angles toward the rest pose (0) instead of toward the initial pose's.
  bool prior_at_rest = false;
};

// Levenberg-Marquardt over the root translation and rotation, every joint's Euler angles (kept
// inside the joint limits by projection) and the scale, minimising the distances to `targets`
// (one per joint, in the skeleton's joint order). `initial` is the starting pose (e.g. the
// previous frame's fit), also the prior's centre. Throws std::invalid_argument when the target
// count differs from the joint count.
JointPoseFit fitPoseToJoints(const Skeleton& skeleton, const std::vector<Eigen::Vector3d>& targets,
                             const JointPoseFit& initial, const JointPoseFitOptions& options = {});

// A starting point for fitPoseToJoints: the rest pose, translated so the root lands on its target,
// and the scale of the targets' extent relative to the rest skeleton's.
JointPoseFit initialJointPoseFit(const Skeleton& skeleton,
                                 const std::vector<Eigen::Vector3d>& targets);

}  // namespace lumistage

namespace lumistage {

struct SkinnedMesh;
// The mesh posed by a fit: linear blend skinning of fit.pose, then scaled by fit.scale about the
// world origin (the same scale as the joints). Outputs are resized only when their size differs.
void posedScaledMesh(const SkinnedMesh& mesh, const JointPoseFit& fit, Eigen::Matrix3Xf& positions,
                     Eigen::Matrix3Xf& normals);

}  // namespace lumistage
