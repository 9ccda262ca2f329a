#pragma once

#include <filesystem>

#include "core/body/skinned_mesh.h"

namespace lumistage {

// Reads a triangle mesh from a binary little-endian PLY as the session writer writes the truth
// surface (truth/surface/NNNNNN.ply: float x, y, z per vertex; faces as a uchar count and int
// indices), and computes its normals. Throws Error naming the file and what was expected.
TriangleMesh readPlyMesh(const std::filesystem::path& path);

}  // namespace lumistage
