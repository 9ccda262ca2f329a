#pragma once

namespace lumistage {

// A progress bar on stderr: redrawn in place on a terminal, a line per tenth otherwise.
void printProgress(const char* what, int done, int total, double ms_per_item = -1);

}  // namespace lumistage
