#pragma once

#include <CLI/CLI.hpp>

namespace lumistage {

// `lumistage export --session DIR --out DIR`: the capture of a session for other tools — the
// skeleton animation as BVH, the captured surface as an animated glTF (and per-frame PLY/OBJ).
void addExportCommand(CLI::App& app);

}  // namespace lumistage
