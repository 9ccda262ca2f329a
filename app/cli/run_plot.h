#pragma once

#include <string>

#include "core/pipeline/studio_coordinator.h"

namespace lumistage {

// A PNG of a pipeline run: each frame's latency against time, with the median and 95th
// percentile, and the frame rate over a sliding second; `caption` (the machine, the session) is
// written under the title. Throws Error when the file cannot be written.
void writeRunPlot(const RunReport& report, const std::string& caption, const std::string& path);

}  // namespace lumistage
