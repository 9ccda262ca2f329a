#pragma once

#include <CLI/CLI.hpp>

namespace lumistage {

// `lumistage keys init|add-node`: the CURVE keys of the studio and its nodes.
void addKeyCommands(CLI::App& app);

}  // namespace lumistage
