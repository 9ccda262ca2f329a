#include "core/base/stop_signal.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <mutex>

namespace lumistage {
namespace {

std::atomic<bool> g_stop{false};
std::atomic<int> g_signal{0};
int g_pipe[2] = {-1, -1};

static_assert(std::atomic<int>::is_always_lock_free, "the handler needs a lock-free atomic");

void onStopSignal(int signal) {
  const int saved_errno = errno;
  int none = 0;
  if (!g_signal.compare_exchange_strong(none, signal)) {
    // The second: the default action, once this handler returns and unblocks the signal.
    std::signal(signal, SIG_DFL);
    std::raise(signal);
    errno = saved_errno;
    return;
  }
  g_stop.store(true);
  if (g_pipe[1] >= 0) {
    const char byte = 1;
    [[maybe_unused]] const ssize_t written = ::write(g_pipe[1], &byte, 1);
  }
  errno = saved_errno;
}

}  // namespace

std::atomic<bool>& stopOnSignals() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (::pipe2(g_pipe, O_CLOEXEC | O_NONBLOCK) != 0) g_pipe[0] = g_pipe[1] = -1;
    struct sigaction action {};
    action.sa_handler = onStopSignal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESTART;  // a blocking read or write goes on; the loops poll the flag
    for (const int signal : {SIGINT, SIGTERM, SIGHUP}) {
      // A signal the program was started ignoring stays ignored: SIGHUP under nohup, SIGINT in
      // a job that a script put in the background.
      struct sigaction old {};
      if (::sigaction(signal, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
      ::sigaction(signal, &action, nullptr);
    }
  });
  return g_stop;
}

int stopSignal() {
  return g_signal.load();
}

const char* stopSignalName(int signal) {
  switch (signal) {
    case SIGINT:
      return "SIGINT (Ctrl-C)";
    case SIGTERM:
      return "SIGTERM";
    case SIGHUP:
      return "SIGHUP";
    default:
      return "a signal";
  }
}

int stopSignalDescriptor() {
  return g_pipe[0];
}

}  // namespace lumistage
