#pragma once

#include <CLI/CLI.hpp>

namespace lumistage {

// `lumistage eval --session DIR [--json FILE]`: accuracy and speed of the studio's stages against
// a virtual-studio session's ground truth (docs/eval-report.md).
void addEvalCommand(CLI::App& app);

}  // namespace lumistage
