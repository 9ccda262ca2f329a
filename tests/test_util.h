#pragma once

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <functional>
#include <string>
#include <system_error>
#include <vector>

#include "core/base/error.h"

namespace lumistage::testing {

// The folders testFolder() made, removed when the test process ends if every test passed (kept
// for a look otherwise: a failure's message names its files).
class TestFolders {
 public:
  ~TestFolders() {
    if (!::testing::UnitTest::GetInstance()->Passed()) return;
    std::error_code ignored;
    for (const std::filesystem::path& folder : folders_)
      std::filesystem::remove_all(folder, ignored);
  }
  void add(const std::filesystem::path& folder) { folders_.push_back(folder); }

 private:
  std::vector<std::filesystem::path> folders_;
};

// An empty folder of the running test's own (ctest runs tests in parallel, as processes).
inline std::filesystem::path testFolder(const std::string& prefix) {
  static TestFolders folders;
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path folder =
      std::filesystem::temp_directory_path() /
      ("lumistage_" + prefix + "_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  folders.add(folder);
  return folder;
}

#ifdef LUMISTAGE_TEST_RESOURCE_DIR
// ../shared/realdata beside the repository: real files made by others (its README says what each
// is), not in a clone; a test that reads one skips without it.
inline std::filesystem::path realData() {
  return std::filesystem::path(LUMISTAGE_TEST_RESOURCE_DIR) / ".." / ".." / "shared" / "realdata";
}
#endif

// The message of the lumistage::Error that `call` throws; a test failure if it throws none.
template <typename Call>
std::string errorOf(Call&& call) {
  try {
    call();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no Error thrown";
  return "no error";
}

// Runs `body` in a child process (fork) and returns its result, or -1 when the child did not end
// normally: for what may not be done to the test process itself (limitFileSize()).
inline int inChildProcess(const std::function<int()>& body) {
  const pid_t child = ::fork();
  if (child < 0) return -1;
  if (child == 0) {
    int code = 100;
    try {
      code = body();
    } catch (...) {
    }
    ::_exit(code);
  }
  int status = 0;
  if (::waitpid(child, &status, 0) != child || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

// A full disk, as far as this process's writes go: no file grows beyond `bytes` (a write past it
// fails with EFBIG instead of the signal); the largest the system allows when `bytes` is 0.
inline void limitFileSize(rlim_t bytes) {
  ::signal(SIGXFSZ, SIG_IGN);
  rlimit limit{};
  ::getrlimit(RLIMIT_FSIZE, &limit);
  limit.rlim_cur = bytes > 0 ? bytes : limit.rlim_max;
  ::setrlimit(RLIMIT_FSIZE, &limit);
}

}  // namespace lumistage::testing
