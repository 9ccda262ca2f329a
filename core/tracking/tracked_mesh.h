#pragma once

#include <Eigen/Core>

#include "core/body/skinned_mesh.h"

namespace lumistage {

// The generic human where the tracker sees the actor: posed by the tracked pose of the
// calibrated skeleton (PoseTracker::skeleton(), the generic one scaled to the actor) and scaled
// by the ratio of the two skeletons' pelvis heights, so that its pelvis lands on the tracked one
// and its feet on the floor. What the refinement starts from, offline (export, eval).
void poseTrackedMesh(const SkinnedMesh& generic, const Skeleton& calibrated, const Pose& tracked,
                     Eigen::Matrix3Xf& positions, Eigen::Matrix3Xf& normals);

}  // namespace lumistage
