#pragma once

#include <CLI/CLI.hpp>

namespace lumistage {

// `lumistage synth`: writes a virtual studio session (images, rig, ground truth).
void addSynthCommand(CLI::App& app);

}  // namespace lumistage
