#pragma once

#include <chrono>

namespace lumistage {

// A file descriptor that polls readable from notify() until clear(): a thread waiting in poll()
// on its sockets is woken at once by another thread with work for it, instead of looking every
// few milliseconds (an eventfd). Throws Error when the system has none to give.
class Wakeup {
 public:
  Wakeup();
  ~Wakeup();
  Wakeup(const Wakeup&) = delete;
  Wakeup& operator=(const Wakeup&) = delete;

  void notify();  // any thread
  void clear();   // the waiting thread, before it looks for the work
  // Waits until notified (since the last clear) or `timeout`; for a thread that has no sockets
  // to poll beside it.
  void wait(std::chrono::milliseconds timeout) const;
  int fd() const { return fd_; }

 private:
  int fd_ = -1;
};

}  // namespace lumistage
