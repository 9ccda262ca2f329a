#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "core/geometry/rig.h"

namespace lumistage {

// The rig file: YAML, documented in docs/rig-file.md. Saving then loading gives back exactly the
// same rig (every double is written in its shortest round-trip form).

// Throws Error with "file:line: key: what was expected, what was found" for anything malformed:
// a missing or unknown key, a non-numeric value, a negative focal length, a matrix that is not a
// rotation, a node naming an unknown camera, a truncated file. Nothing is silently defaulted
// except what docs/rig-file.md calls optional.
Rig loadRig(const std::filesystem::path& path);
// The same, from text; source_name is used in messages in place of a file name.
Rig parseRig(std::string_view yaml_text, std::string_view source_name);

void saveRig(const Rig& rig, const std::filesystem::path& path);  // atomic: write, then rename
std::string formatRig(const Rig& rig);

}  // namespace lumistage
