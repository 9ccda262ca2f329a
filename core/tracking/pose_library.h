#pragma once

#include <vector>

#include "core/body/skeleton.h"

namespace lumistage {

// The poses the tracker starts from when it does not know how the actor stands: every pose of the
// built-in clips (motion_library.h: walking, waving, turning, crouching, the T- and A-pose), a
// tenth of a second apart, each also bent forward at the hips by 0.6 and 1.2 rad, sitting on the
// floor (sittingOnTheFloor: T- and A-pose arms, upright and leaning back, legs out, knees up and
// tucked), and each one's mirror image, for `skeleton` (the human skeleton's 24 joints). Each is
// turned to face +y and stood over the origin (root x and y zero, its height as in its clip); poses
// whose joints lie within `min_spacing_m` on average of a pose already taken are left out. The
// T-pose comes first.
std::vector<Pose> makeInitialisationPoses(const Skeleton& skeleton, double min_spacing_m = 0.04);

// Sitting on the floor, facing +y: `arms`' arms (its spine straightened, its root level), the torso
// leaned back by `lean_rad`, both knees bent by `knee_rad` (0: legs straight out) and the thighs
// raised forward by half that above level (as far as the hips' limits allow), so that heels and
// seat rest on the floor together. Root x and y zero, its height as the rest pose's (whoever
// places it stands its lowest point on the floor).
Pose sittingOnTheFloor(const Skeleton& skeleton, const Pose& arms, double lean_rad,
                       double knee_rad);

// The pose's mirror image through the body's sagittal plane (x = 0 in the rest pose): left and
// right joints swapped, every angle's y and z negated (the human skeleton's limits mirror so), the
// root's rotation and its x translation mirrored.
Pose mirroredPose(const Pose& pose);

// The pose's root turned about the vertical so that its facing (+y of the root) points along +y,
// its root moved over the origin (x and y zero).
Pose uprightFacingForward(const Pose& pose);

}  // namespace lumistage
