#include "core/base/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <system_error>

#include "core/base/error.h"

namespace lumistage {

std::string readFile(const std::filesystem::path& path) {
  // Opened without blocking and checked before a byte is read: a FIFO where a file was expected
  // would block the open (and the program) for ever, a device (/dev/zero) would fill memory.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw Error(path.string() + ": cannot open: " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    const bool folder = S_ISDIR(st.st_mode);
    ::close(fd);
    throw Error(path.string() + (folder ? ": is a folder, expected a file"
                                        : ": is not a regular file (a FIFO, a socket or a "
                                          "device?), expected a file"));
  }
  std::string out;
  // (Files under /proc say size 0 and have more: read to the end whatever the size said.)
  out.reserve(static_cast<size_t>(st.st_size));
  char buffer[65536];
  while (true) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int error = errno;
      ::close(fd);
      throw Error(path.string() + ": read error: " + std::strerror(error));
    }
    if (n == 0) break;
    out.append(buffer, static_cast<size_t>(n));
  }
  ::close(fd);
  return out;
}

namespace {

// Writes all of `data` to `fd`, again where interrupted. False (errno set; `written`: what went
// out) on a failure, or when nothing more goes out (ENOSPC).
bool writeAll(int fd, std::string_view data, size_t& written) {
  written = 0;
  while (written < data.size()) {
    const ssize_t n = ::write(fd, data.data() + written, data.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (n == 0) errno = ENOSPC;
      return false;
    }
    written += static_cast<size_t>(n);
  }
  return true;
}

// A failed write's errno in words, a full disk said as such.
std::string writeErrorText(int error) {
  return std::string(std::strerror(error)) +
         (error == ENOSPC || error == EFBIG ? " (disk full?)" : "");
}

}  // namespace

bool isAtomicWriteLeftover(std::string_view file_name) {
  const size_t at = file_name.rfind(".tmp-");
  return at != std::string_view::npos && file_name.size() - at == 11;
}

void writeFileAtomically(const std::filesystem::path& path, std::string_view contents,
                         const AtomicWriteOptions& options) {
  writeFileAtomically(path, {contents}, options);
}

void writeFileAtomically(const std::filesystem::path& path,
                         std::initializer_list<std::string_view> pieces,
                         const AtomicWriteOptions& options) {
  const std::string target = path.string();
  std::string temp = target + ".tmp-XXXXXX";
  const int fd = ::mkstemp(temp.data());
  if (fd < 0)
    throw Error(target + ": cannot create a temporary file beside it: " + std::strerror(errno));
  auto fail = [&](const char* step) {
    const int saved = errno;
    ::close(fd);
    ::unlink(temp.c_str());
    throw Error(target + ": " + step + " failed: " + writeErrorText(saved));
  };
  size_t written = 0;
  for (const std::string_view contents : pieces)
    if (!writeAll(fd, contents, written)) fail("write");
  if (::fchmod(fd, static_cast<mode_t>(options.mode)) != 0) fail("chmod");
  if (options.sync && ::fsync(fd) != 0) fail("fsync");
  if (::close(fd) != 0) {
    const int saved = errno;
    ::unlink(temp.c_str());
    throw Error(target + ": close failed: " + std::strerror(saved));
  }
  if (::rename(temp.c_str(), target.c_str()) != 0) {
    const int saved = errno;
    ::unlink(temp.c_str());
    throw Error(target + ": rename into place failed: " + std::strerror(saved));
  }
}

AppendOnlyFile::~AppendOnlyFile() {
  if (fd_ >= 0) ::close(fd_);
}

void AppendOnlyFile::create(const std::filesystem::path& path) {
  if (fd_ >= 0) ::close(fd_);
  path_ = path;
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw Error(path.string() + ": cannot create: " + std::strerror(errno));
  length_ = 0;
  failed_ = false;
  error_.clear();
}

bool AppendOnlyFile::append(std::string_view record) {
  if (failed_ || fd_ < 0) return false;
  size_t written = 0;
  if (!writeAll(fd_, record, written)) {
    error_ = writeErrorText(errno);
    failed_ = true;
    // Back to the last whole record (a reader would skip a torn last line, but not one that a
    // later write completed into something else).
    if (written > 0 && ::ftruncate(fd_, static_cast<off_t>(length_)) != 0)
      error_ += std::string("; and cutting it back failed: ") + std::strerror(errno);
    return false;
  }
  length_ += static_cast<int64_t>(record.size());
  return true;
}

}  // namespace lumistage
