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

// Positions and normals of `body` posed by `data`; reuses the buffers (no allocation once sized).
void posedBodyMesh(const SkinnedMesh& body, const PoseData& data,
                   std::vector<Eigen::Affine3f>& transforms, Eigen::Matrix3Xf& positions,
                   Eigen::Matrix3Xf& normals);

}  // namespace lumistage
