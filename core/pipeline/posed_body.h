#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "core/body/skinned_mesh.h"
#include "core/net/message_codec.h"

namespace lumistage {

// The generic human as the studio's pose message places it (what every node poses, and the
// studio draws): the tracked angles, then the body scaled by `scale` about the world origin (the
// floor's centre) so that a taller or shorter actor is matched, its pelvis landing at
// scale * (rest pelvis + root).
Pose poseFromMessage(const PoseData& data, int joint_count);

// The message for a pose tracked on the calibrated skeleton (PoseTracker::skeleton(): the generic
// one fitted to the actor) that poses the generic human, whose rest pelvis is at `generic_root_m`:
// the same angles, the body scaled by the ratio of the two pelvis heights (its feet stay on the
// floor, its head reaches the actor's), the root such that the pelvis lands on the tracked one.
PoseData poseMessageFor(const Eigen::Vector3d& generic_root_m, const Skeleton& calibrated,
                        const Pose& tracked);

// Positions and normals of `body` posed by `data`; reuses the buffers (no allocation once sized).
void posedBodyMesh(const SkinnedMesh& body, const PoseData& data,
                   std::vector<Eigen::Affine3f>& transforms, Eigen::Matrix3Xf& positions,
                   Eigen::Matrix3Xf& normals);

}  // namespace lumistage
