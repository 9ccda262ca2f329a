#pragma once

#include <CLI/CLI.hpp>

namespace lumistage {

// `lumistage eval`: accuracy of a virtual-studio session's reconstruction against its truth.
void addEvalCommand(CLI::App& app);

}  // namespace lumistage
