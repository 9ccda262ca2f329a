#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

struct aiScene;

namespace lumistage {

// How an imported file's axes and units become ours (z up, the actor facing +y, +x the actor's
// right, metres: skeleton.h), for loadSkinnedMesh (mesh_io.h).

// Which way a skeleton stands, from its joints' names and rest positions (in any one frame).
// `up` runs from the feet (joints whose names hold "foot", "toe", "ankle" or "heel") to the head
// ("head", else "neck"); `left` from the right side's joints to the left side's (names with a word
// "left"/"l" or "right"/"r": LeftFoot, leg_joint_L_5, Bip01 L Foot, foot.L), across `up`. Each is
// snapped to the nearest coordinate axis (±x, ±y, ±z) and is nullopt where the names do not tell or
// the direction lies more than 35 degrees from every axis.
struct SkeletonAxes {
  std::optional<Eigen::Vector3f> up;
  std::optional<Eigen::Vector3f> left;
};
SkeletonAxes skeletonAxes(const std::vector<std::string>& names,
                          const std::vector<Eigen::Vector3f>& positions);

// The map from a scene's coordinates, as Assimp gives them, to ours in metres: a rotation (a
// mirror where the file is left-handed) times the length of the file's unit in metres. Per format
// (Assimp's importer, from the scene's metadata):
// - glTF: +Y up, the actor facing +Z, metres (the specification's).
// - FBX: the file's GlobalSettings, which Assimp passes on without applying them: UpAxis,
//   FrontAxis and CoordAxis (the actor's left) with their signs, UnitScaleFactor (centimetres per
//   unit).
// - COLLADA: Assimp has applied <up_axis> and <unit> already, giving +Y up and metres.
// - Assimp's own formats (assbin, ...): Assimp's convention, +Y up, +Z front, metres.
// - DirectX .X: +Y up (Assimp has made the left-handed axes right-handed), +Z front, metres, by
//   convention only: many exporters write their own Z-up axes into it. The skeleton decides
//   (skeletonAxes) when its names tell; where it overrides the convention a warning says so.
// - any other format: no axes of its own; the skeleton's as for .X, else Assimp's convention,
//   with a warning either way.
// A skeleton standing against a declared up axis (a glTF lying down) gets a warning, and the
// file's axes are kept. Throws Error naming the file: FBX axis settings that are not three
// different axes with signs ±1, or a unit scale that is not a positive finite number.
Eigen::Matrix3f sceneToOurs(const aiScene& scene, const std::filesystem::path& path,
                            const SkeletonAxes& skeleton);

}  // namespace lumistage
