#pragma once

#include <filesystem>
#include <string_view>

namespace lumistage {

// Limits on the nesting of a glTF file that checkGltfNesting enforces.
struct GltfNestingLimits {
  int json_depth = 512;   // arrays and objects within each other
  int node_depth = 1000;  // nodes, each the child of the one before
};

// Checks a glTF file (.gltf JSON, or the JSON chunk of a .glb) before Assimp reads it: Assimp's
// JSON parser and its node import recurse per level, and a file 30,000 levels deep crashed them
// with a stack overflow. Refuses, with an Error naming the file, JSON nested deeper than the
// limits, a node hierarchy deeper than them, and one that is not a set of trees (a node that is the
// child of two, or of itself through others: the spec forbids both, and an importer that copies a
// subtree per parent grows exponentially). Any other file is left to Assimp, as are a .glb's or
// JSON's other flaws.
void checkGltfNesting(const std::filesystem::path& path, const GltfNestingLimits& limits = {});

// The same on a glTF document's JSON text; `file` names it in errors.
void checkGltfJsonNesting(std::string_view json, std::string_view file,
                          const GltfNestingLimits& limits = {});

}  // namespace lumistage
