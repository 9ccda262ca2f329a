#pragma once

#include <CLI/CLI.hpp>

namespace lumistage {

// `lumistage cameras`, `lumistage virtual-cameras`, `lumistage stream`: acquisition.
void addCameraCommands(CLI::App& app);

}  // namespace lumistage
