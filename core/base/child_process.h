#pragma once

#include <chrono>
#include <functional>

#include "core/base/status.h"

namespace lumistage {

// Runs `work` in a child process (fork), so that a crash inside a library it calls (Assimp
// overflowing its parser's stack on a file nested too deep) ends the child and not the caller.
// Ok when `work` returned; failed with the text of what it threw; failed with "crashed (SIGNAL)"
// when the child died of a signal. The child writes to the caller's stdout and stderr (flushed
// before the fork), and dies of a crash whatever handlers the caller set. For work that reads and
// checks a file: the child has only the calling thread, so `work` must not wait on what another
// thread of the caller holds; should it hang all the same, it is killed after `limit`, and the
// result says so.
Status runInChildProcess(const std::function<void()>& work,
                         std::chrono::seconds limit = std::chrono::seconds(120));

}  // namespace lumistage
