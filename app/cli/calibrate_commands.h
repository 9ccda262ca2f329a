#pragma once

#include <CLI/CLI.hpp>

namespace lumistage {

// `lumistage calibrate wand|board|synth-wand|synth-board`: self-calibration of the rig from a
// wand session, calibration from checkerboard views, and simulated sessions of both.
void addCalibrateCommands(CLI::App& app);

}  // namespace lumistage
