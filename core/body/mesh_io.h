#pragma once

#include <filesystem>

#include "core/body/skinned_mesh.h"

namespace lumistage {

// Skinned meshes in files, through Assimp.
//
// Axes: ours is z up, facing +y, +x right (skeleton.h), in metres. glTF is +Y up with the asset
// facing +Z (so +X is the actor's left), in metres: saveSkinnedMeshGltf converts, so a saved actor
// stands upright in any glTF viewer. loadSkinnedMesh converts each format's axes and units
// (mesh_axes.h): glTF's, an FBX file's GlobalSettings (up, front and side axes, UnitScaleFactor),
// COLLADA's <up_axis> and <unit>, DirectX .X's Y up left-handed convention, and where a format
// cannot tell (or, for .X, its skeleton stands otherwise) the skeleton's own head-above-feet
// direction, with a warning. A body that stands outside 0.2 to 3 m tall gets a warning about units.

// Writes glTF 2.0: binary (.glb) or JSON with a .bin buffer beside it (.gltf), chosen by the
// extension. One mesh (positions, normals, triangles), the skeleton as a node hierarchy (node
// names = joint names, translations = rest offsets), one bone per joint with its inverse bind
// matrix, up to four weights per vertex. Per-vertex materials, when present, go in texture
// coordinate set 0 (u = material index, v = 0) of a material named "lumistage_vertex_materials".
// The files appear atomically (.glb) or .bin first then .gltf (.gltf). Throws Error naming the
// file: unknown extension, invalid mesh, export or rename failure.
void saveSkinnedMeshGltf(const SkinnedMesh& mesh, const std::filesystem::path& path);

// Reads any rigged, skinned mesh Assimp reads (glTF/GLB, FBX, COLLADA, DirectX .X, ...). Identical
// vertices are joined, polygons triangulated, missing normals generated. The skeleton is the bone
// nodes and their ancestors up to the lowest common one; rest positions come from the bind pose
// (our rest frames are world aligned, so a bind pose with rotated joint frames keeps only its
// positions). Several meshes are merged when they share the skeleton. Joint limits come from the
// human skeleton when a joint's name is one of ours (or a common alias, see humanJointNameFor in
// bvh.h), else ±pi on every axis. A vertex with more than four bone influences keeps the four
// largest (Assimp's aiProcess_LimitBoneWeights), renormalised to sum 1, and one warning names the
// file and how many vertices had more; bones left without weights stay joints. Throws Error naming
// the file: unreadable or unsupported (with Assimp's reason), no mesh, no bones, meshes on
// different skeletons, a vertex without weights, a weight on a vertex that does not exist, FBX
// axis settings that make no frame (mesh_axes.h).
SkinnedMesh loadSkinnedMesh(const std::filesystem::path& path);

}  // namespace lumistage
