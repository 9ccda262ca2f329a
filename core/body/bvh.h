#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "core/body/motion_clip.h"
#include "core/body/skeleton.h"

namespace lumistage {

// BVH (Biovision hierarchy) motion files.
//
// Axes: a BVH file is taken as +Y up with the actor facing +Z in its rest pose (so +X is the
// actor's left), the convention of CMU, Mixamo and Blender exports; ours is z up, facing +y, +x
// right (skeleton.h). The rest pose (every channel zero) is taken to be a T-pose like ours, so a
// joint's rotation relative to rest means the same thing in both. Nothing is detected: a file
// facing another way comes in turned.
//
// Root motion: a joint's position channels are its absolute position in its parent's frame (they
// replace its OFFSET, as Blender reads them). The root's translation is measured from the rest
// skeleton standing on the floor (root height = rest root height above its lowest joint or end
// site) and scaled by our pelvis height / the file's pelvis height, both measured that way. That
// ratio also converts the units (centimetres, inches, metres), so no unit is guessed.

// How a skeleton names its spine and arms. kGeneric (Mixamo and most FBX exports): Spine, Spine1,
// Spine2, and Shoulder the clavicle; kCmu (a skeleton with a LowerBack): LowerBack, Spine, Spine1;
// kBiovision (one with Collar joints): Ab, Chest, Collar the clavicle and Shoulder the upper arm.
enum class JointNaming { kGeneric, kCmu, kBiovision };

// Our human joint name for a common BVH / FBX joint name (CMU, Biovision, Mixamo with or without
// its "mixamorig:" prefix, generic), or the name itself when it already is one of ours; nullopt
// when unknown.
std::optional<std::string> humanJointNameFor(std::string_view name,
                                             JointNaming naming = JointNaming::kGeneric);

// Reads a BVH file and retargets it onto `target` by joint name (same name, else
// humanJointNameFor). Each mapped target joint takes the world rotation of its source joint,
// after the turn that brings its bone (to its first mapped child) onto the file's at rest: a rest
// pose that is not ours (legs splayed, arms down) moves the bones as the file moves them;
// rotations of unmapped source joints are thereby folded into their mapped descendants; a target
// joint with no source stays at zero. Nothing is clamped to joint limits. Throws Error with file
// and line: missing braces or keywords, unknown channel names, non-numeric values, a frame line
// with the wrong number of values, fewer frames than announced, no joint mapping to the target.
MotionClip loadBvh(const std::filesystem::path& path, const Skeleton& target);

// Writes a clip of `skeleton` as BVH, in our joint names, Y up, centimetres, channels
// "Xrotation Yrotation Zrotation" (the root also "Xposition Yposition Zposition" first), floor at
// y = 0: loadBvh of the file onto the same skeleton gives the same joint positions. Atomic write;
// throws Error naming the file.
void saveBvh(const MotionClip& clip, const Skeleton& skeleton, const std::filesystem::path& path);

}  // namespace lumistage
