#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "core/sim/stage_draw.h"

namespace lumistage {

// `lumistage corpus`: films the randomised virtual stages of a range of seeds (drawStage) and
// evaluates motion capture on each, with a table and JSON of every stage and the corpus's mean
// and worst figures (docs/virtual-studio.md, "The randomised corpus").
void addCorpusCommand(CLI::App& app);

// The options `synth --seed` and `corpus` share: --cameras MIN-MAX, --motions DIR, --start.
void addStageDrawOptions(CLI::App& command, StageDrawOptions& options);
// "1000-1019", "7", "1,2,5-9": the seeds in order, each once. Throws Error naming what it expected.
std::vector<uint32_t> parseSeeds(const std::string& text);

}  // namespace lumistage
