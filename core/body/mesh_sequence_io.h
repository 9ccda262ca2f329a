#pragma once

#include <filesystem>
#include <vector>

#include "core/body/skinned_mesh.h"

namespace lumistage {

// Captured surfaces in files, for the tools users carry a capture into (Blender, Maya, Houdini,
// game engines). All write atomically and throw Error naming the file. Lengths are metres; files
// in glTF take glTF's axes (Y up, facing +Z), as mesh_io.h does; PLY and OBJ keep ours (z up).

// Binary PLY: positions and triangles (what truth/surface/*.ply holds).
void saveMeshPly(const std::filesystem::path& path, const TriangleMesh& mesh);
// Wavefront OBJ: positions, normals, triangles.
void saveMeshObj(const std::filesystem::path& path, const TriangleMesh& mesh);

// A mesh sequence as one animated binary glTF (.glb): a node per frame holding that frame's mesh,
// shown during its frame only (its scale steps from 0 to 1 and back: the portable way to play a
// mesh sequence; every glTF reader understands node animation, while morph-target sequences of
// hundreds of targets are not). Triangles shared by every frame (the refined generic mesh) are
// stored once. Frame i is shown from i / fps seconds.
void saveMeshSequenceGlb(const std::filesystem::path& path, const std::vector<TriangleMesh>& frames,
                         double fps);

}  // namespace lumistage
