#pragma once

#include <CLI/CLI.hpp>

namespace lumistage {

// `lumistage video recover`: a whole video of the recording of a view that never closed.
void addVideoCommands(CLI::App& app);

}  // namespace lumistage
