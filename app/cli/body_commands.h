#pragma once

#include <CLI/CLI.hpp>

namespace lumistage {

// `lumistage body generate|show`: the generic human and other rigged meshes.
void addBodyCommands(CLI::App& app);

}  // namespace lumistage
