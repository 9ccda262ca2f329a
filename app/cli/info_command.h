#pragma once

#include <CLI/CLI.hpp>

namespace lumistage {

// `lumistage info`: the version, where resources and shaders are found, and which OpenGL device
// renders (a GPU, or Mesa's software renderer) — the first thing to check on a new PC.
void addInfoCommand(CLI::App& app);

}  // namespace lumistage
