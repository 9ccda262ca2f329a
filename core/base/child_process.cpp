#include "core/base/child_process.h"

#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

namespace lumistage {

Status runInChildProcess(const std::function<void()>& work, std::chrono::seconds limit) {
  int fds[2];
  if (::pipe(fds) != 0) return Status::failure(std::string("pipe: ") + std::strerror(errno));
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int error = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    return Status::failure(std::string("fork: ") + std::strerror(error));
  }
  if (pid == 0) {
    ::close(fds[0]);
    // A crash ends the child by its signal: handlers inherited from the caller (a test
    // framework's, which would fork a debugger from inside a crashed malloc) are not run.
    for (const int crash : {SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL}) std::signal(crash, SIG_DFL);
    std::string error;
    try {
      work();
    } catch (const std::exception& e) {
      error = *e.what() != '\0' ? e.what() : "failed";
    } catch (...) {
      error = "failed";
    }
    std::fflush(stdout);
    std::fflush(stderr);
    for (size_t done = 0; done < error.size();) {
      const ssize_t n = ::write(fds[1], error.data() + done, error.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      done += size_t(n);
    }
    ::_exit(error.empty() ? 0 : 1);  // no destructors or atexit handlers of the caller's
  }
  ::close(fds[1]);
  // The child's error text until it ends (the pipe's end closes), or the limit.
  std::string error;
  char buffer[4096];
  const auto deadline = std::chrono::steady_clock::now() + limit;
  bool late = false;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    pollfd ready{fds[0], POLLIN, 0};
    const int polled = ::poll(&ready, 1, int(std::max<int64_t>(left.count(), 0)));
    if (polled < 0 && errno == EINTR) continue;
    if (polled == 0) {
      late = true;
      ::kill(pid, SIGKILL);
      break;
    }
    const ssize_t n = ::read(fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    error.append(buffer, size_t(n));
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (late)
    return Status::failure("took longer than " + std::to_string(limit.count()) + " s: stopped");
  if (WIFSIGNALED(status))
    return Status::failure(std::string("crashed (") + ::strsignal(WTERMSIG(status)) + ")");
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    return Status::failure(error.empty() ? "failed" : error);
  return {};
}

}  // namespace lumistage
