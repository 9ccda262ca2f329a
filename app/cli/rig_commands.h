#pragma once

#include <CLI/CLI.hpp>

namespace lumistage {

// `lumistage rig show|import|ring`: registers the subcommands on `app`.
void addRigCommands(CLI::App& app);

}  // namespace lumistage
