#include "core/base/stop_signal.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <csignal>

namespace lumistage {
namespace {

// Each case runs in a child process (a death test): the handlers are the process's.

// The first signal asks to stop and wakes an event loop; the second ends the program as the
// signal would without a handler.
TEST(StopSignalDeathTest, TheFirstSignalAsksToStopTheSecondEndsTheProgram) {
  EXPECT_EXIT(
      {
        std::atomic<bool>& stop = stopOnSignals();
        if (stop || stopSignal() != 0 || stopSignalDescriptor() < 0) _exit(3);
        char byte = 0;
        if (::read(stopSignalDescriptor(), &byte, 1) != -1) _exit(4);  // nothing to read yet
        std::raise(SIGTERM);
        if (!stop || stopSignal() != SIGTERM) _exit(5);
        if (::read(stopSignalDescriptor(), &byte, 1) != 1) _exit(6);
        if (&stopOnSignals() != &stop) _exit(7);  // installed once, one flag
        std::raise(SIGINT);
        _exit(8);  // not reached: SIGINT's default action ends the program
      },
      ::testing::KilledBySignal(SIGINT), "");
}

// Started ignoring SIGHUP (nohup), the program goes on ignoring it, and still stops on SIGINT.
TEST(StopSignalDeathTest, ASignalTheProgramWasStartedIgnoringStaysIgnored) {
  EXPECT_EXIT(
      {
        std::signal(SIGHUP, SIG_IGN);
        const std::atomic<bool>& stop = stopOnSignals();
        std::raise(SIGHUP);
        if (stop || stopSignal() != 0) _exit(3);
        std::raise(SIGINT);
        _exit(stop && stopSignal() == SIGINT ? 0 : 4);
      },
      ::testing::ExitedWithCode(0), "");
}

TEST(StopSignal, NamesTheSignalsItHandles) {
  EXPECT_STREQ(stopSignalName(SIGINT), "SIGINT (Ctrl-C)");
  EXPECT_STREQ(stopSignalName(SIGTERM), "SIGTERM");
  EXPECT_STREQ(stopSignalName(SIGHUP), "SIGHUP");
}

}  // namespace
}  // namespace lumistage
