// Work run in a child process: what it returns, throws or crashes of comes back to the caller,
// which lives on.
#include "core/base/child_process.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <stdexcept>

#include "core/base/error.h"

namespace lumistage {
namespace {

TEST(ChildProcess, ReturnsWhatTheWorkDidAndSurvivesItsCrash) {
  int here = 0;
  EXPECT_TRUE(runInChildProcess([&] { here = 1; }).ok());
  EXPECT_EQ(here, 0) << "the work ran in this process, not a child";
  const Status thrown = runInChildProcess([] { throw Error("model.dae:3: no <scene>"); });
  ASSERT_FALSE(thrown.ok());
  EXPECT_EQ(thrown.error(), "model.dae:3: no <scene>");
  const Status crashed = runInChildProcess([] { std::raise(SIGSEGV); });
  ASSERT_FALSE(crashed.ok());
  EXPECT_EQ(crashed.error().rfind("crashed (", 0), 0u) << crashed.error();
  const Status aborted = runInChildProcess([] { std::abort(); });
  EXPECT_NE(aborted.error().find("crashed ("), std::string::npos) << aborted.error();
  EXPECT_EQ(runInChildProcess([] { throw std::runtime_error(""); }).error(), "failed");
  // Work that never ends is stopped at its limit.
  const Status hung = runInChildProcess([] { pause(); }, std::chrono::seconds(1));
  EXPECT_EQ(hung.error(), "took longer than 1 s: stopped");
}

}  // namespace
}  // namespace lumistage
