#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "core/body/motion_clip.h"
#include "core/body/skeleton.h"

namespace lumistage {

// Motions generated in code, for synthetic captures and tests: no data files to ship, and they fit
// any human skeleton (makeHumanSkeleton() with any BodyShape).
//
// Every clip starts exactly in the skeleton's rest T-pose (trackers initialise from it) and blends
// into its motion within about 0.5 s, keeps every angle inside the joint limits, keeps the root
// within 1 m of the stage centre, and stands on the floor: each frame's root height puts the lowest
// point of either sole at z = 0.
//   walk         clockwise (seen from above) round a circle of radius 0.6 m about the stage centre,
//                entered by a half circle from the centre; for a 1.75 m body a gait cycle of 1.1 s
//                and 0.9 m (two steps of 0.45 m): 0.8 m/s. Longer legs take longer, slower steps.
//   arm_wave     standing, right arm raised waving hello, left arm down; slow weight shift.
//   turn         turning on the spot through a full 360 degrees (counter-clockwise seen from
//                above) with small steps, arms in an A-pose.
//   crouch       squatting down and up twice (pelvis about 0.4 m lower), feet flat and in place,
//                torso leaning forward, arms reaching forward.
//   a_pose_hold  lowering the arms from the T-pose to an A-pose (0.75 rad below level) over 1 s,
//                then holding it and breathing.
std::vector<std::string> builtinClipNames();

// Throws std::invalid_argument for an unknown name (the message lists the valid ones), a skeleton
// that does not have the 24 joints of makeHumanSkeleton() in order, or a non-positive fps or
// duration. Frames: round(duration_s * fps) + 1.
MotionClip makeBuiltinClip(std::string_view name, const Skeleton& skeleton, double fps = 30.0,
                           double duration_s = 4.0);

}  // namespace lumistage
