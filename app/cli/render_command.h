#pragma once

#include <CLI/CLI.hpp>

namespace lumistage {

// `lumistage render`: a camera path through a recorded session, rendered with the unstructured
// lumigraph into a video.
void addRenderCommand(CLI::App& app);

}  // namespace lumistage
