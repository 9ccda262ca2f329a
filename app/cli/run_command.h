#pragma once

#include <CLI/CLI.hpp>

namespace lumistage {

// `lumistage run`: the distributed pipeline on one machine, nodes as real processes.
void addRunCommand(CLI::App& app);

}  // namespace lumistage
