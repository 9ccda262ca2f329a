#include "core/pipeline/wakeup.h"

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <string>

#include "core/base/error.h"

namespace lumistage {

Wakeup::Wakeup() : fd_(eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
  if (fd_ < 0) throw Error(std::string("cannot make an eventfd: ") + std::strerror(errno));
}

Wakeup::~Wakeup() {
  close(fd_);
}

void Wakeup::notify() {
  const uint64_t one = 1;
  // Fails only when the counter would overflow: it is readable then anyway.
  [[maybe_unused]] const ssize_t n = write(fd_, &one, sizeof one);
}

void Wakeup::clear() {
  uint64_t count = 0;
  [[maybe_unused]] const ssize_t n = read(fd_, &count, sizeof count);  // EAGAIN when not set
}

void Wakeup::wait(std::chrono::milliseconds timeout) const {
  pollfd item{fd_, POLLIN, 0};
  poll(&item, 1, static_cast<int>(timeout.count()));
}

}  // namespace lumistage
