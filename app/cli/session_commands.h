#pragma once

#include <CLI/CLI.hpp>

namespace lumistage {

// `lumistage session merge`: joins the parts of a take that the camera nodes recorded, each on
// its own PC, into one session of every camera.
void addSessionCommands(CLI::App& app);

}  // namespace lumistage
