#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "core/body/skinned_mesh.h"
#include "core/net/message_types.h"

namespace lumistage {

// The generic human as the studio's pose message places it (what every node poses, and the
// studio draws): the tracked angles, then the body scaled by `scale` about the world origin (the
// floor's centre) so that a taller or shorter actor is matched, its pelvis landing at
// scale * (rest pelvis + root).
Pose poseFromMessage(const PoseData& data, int joint_count);
// The same into `pose`, its buffer reused (no allocation once sized).
void poseFromMessage(const PoseData& data, int joint_count, Pose& pose);

// The message that poses the nodes' generic human (skeleton `generic`) where the tracker found the
// actor. The tracker's skeleton (PoseTracker::skeleton()) is the generic one with the actor's
// proportions (legs, height), so the tracked angles alone would put the generic skeleton's joints
// elsewhere: a crouching actor's longer legs fold further than the generic ones. The generic
// skeleton is scaled uniformly to the calibrated one (least squares over their rest joints: fixed
// for an actor, no shimmer) and its pose fitted to the tracked joints (`joints`, world, metres),
// starting from the tracked angles; the twists about the bones, which joint positions leave
// unobserved, are drawn toward the rest pose's. Against the tracked angles scaled by the pelvis
// heights, on the four reference clips: leave-one-camera-out matte 24.30 / 23.69 / 23.95 / 23.23
// -> 24.43 / 23.70 / 24.19 / 23.57 dB, best offsets 28.0 / 25.4 / 27.1 / 24.8 -> 28.4 / 27.2 / 28.2
// / 26.9 dB (docs/lumigraph.md). The fit: 1.2 ms.
PoseData poseMessageFor(const Skeleton& generic, const Skeleton& calibrated, const Pose& tracked,
                        const std::vector<Eigen::Vector3d>& joints);

// Positions and normals of `body` posed by `data`; `pose` and `transforms` are working buffers.
// All are reused: once sized, nothing allocates (tests/core/hot_path_test.cpp).
void posedBodyMesh(const SkinnedMesh& body, const PoseData& data, Pose& pose,
                   std::vector<Eigen::Affine3f>& transforms, Eigen::Matrix3Xf& positions,
                   Eigen::Matrix3Xf& normals);

}  // namespace lumistage
