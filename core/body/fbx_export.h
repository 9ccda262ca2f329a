#pragma once

#include <filesystem>

#include "core/body/motion_clip.h"
#include "core/body/skinned_mesh.h"

namespace lumistage {

// FBX through Assimp's exporter, for Blender, Maya, MotionBuilder, Unity and Unreal.
enum class FbxEncoding {
  kBinary,  // what Blender reads (its importer refuses ASCII FBX); Assimp 5.2 cannot read it back
  kAscii,   // FBX 7.4 ASCII: Assimp reads it back, Blender does not
};

// Writes `body` (its skeleton, mesh and skin) and `clip` (poses of body.skeleton) as one FBX
// scene: a root node "lumistage_actor" holding the skeleton's joint nodes (named as the joints,
// each bone of the skin on the node of its name) and a node "body" holding the skinned mesh; one
// animation take named after the clip, a key per frame on every joint (translation, rotation,
// scale) at the clip's rate. The whole scene is scaled by `scale` about the origin (the tracked
// actor's size against the generic body, posed_body.h). Axes: FBX's Y up, facing +Z (our z up,
// facing +y converted, skeleton.h's yUpToOurs); units: centimetres, FBX's and Assimp's default
// (UnitScaleFactor 1), so the body stands its height in Blender. Time: the file's frame rate
// (TimeMode, CustomFrameRate), timeline and take end are the clip's (Assimp writes 24 fps and one
// second; they are set in its file). The file appears whole (written beside its name, then put in
// its place). Throws Error naming the file: an invalid body, a clip whose
// poses are not of its skeleton, an export or rename failure.
void saveAnimatedBodyFbx(const SkinnedMesh& body, const MotionClip& clip,
                         const std::filesystem::path& file, double scale = 1,
                         FbxEncoding encoding = FbxEncoding::kBinary);

}  // namespace lumistage
