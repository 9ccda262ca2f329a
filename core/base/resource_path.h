#pragma once

#include <filesystem>
#include <string_view>

namespace lumistage {

// The path of a file under Lumistage's resources/ (e.g. "rigs/reference.yaml"). Looked for, in
// order: $LUMISTAGE_RESOURCE_DIR, <executable>/../share/lumistage/resources (an installed
// package), the source tree the build came from. Throws Error naming every place it looked.
std::filesystem::path resourcePath(std::string_view relative);

// The same for a GLSL file under shaders/ ($LUMISTAGE_SHADER_DIR, <executable>/../share/
// lumistage/shaders, the source tree).
std::filesystem::path shaderPath(std::string_view relative);

}  // namespace lumistage
