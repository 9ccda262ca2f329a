#include "core/base/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <system_error>

#include "core/base/error.h"

namespace lumistage {

std::string readFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw Error(path.string() + ": is a folder, expected a file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot open: " + std::strerror(errno));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw Error(path.string() + ": read error");
  return buffer.str();
}

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
    throw Error(target + ": " + step + " failed: " + std::strerror(saved) +
                (saved == ENOSPC || saved == EFBIG ? " (disk full?)" : ""));
  };
  for (const std::string_view contents : pieces) {
    size_t written = 0;
    while (written < contents.size()) {
      const ssize_t n = ::write(fd, contents.data() + written, contents.size() - written);
      if (n < 0) {
        if (errno == EINTR) continue;
        fail("write");
      }
      written += static_cast<size_t>(n);
    }
  }
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
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw Error(path.string() + ": cannot create: " + std::strerror(errno));
  length_ = 0;
  failed_ = false;
  error_.clear();
}

bool AppendOnlyFile::append(std::string_view record) {
  if (failed_ || fd_ < 0) return false;
  size_t written = 0;
  while (written < record.size()) {
    const ssize_t n = ::write(fd_, record.data() + written, record.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int saved = n < 0 ? errno : ENOSPC;
      error_ = std::string(std::strerror(saved)) +
               (saved == ENOSPC || saved == EFBIG ? " (disk full?)" : "");
      failed_ = true;
      // Back to the last whole record (a reader would skip a torn last line, but not one that a
      // later write completed into something else).
      if (written > 0 && ::ftruncate(fd_, static_cast<off_t>(length_)) != 0)
        error_ += std::string("; and cutting it back failed: ") + std::strerror(errno);
      return false;
    }
    written += static_cast<size_t>(n);
  }
  length_ += static_cast<int64_t>(record.size());
  return true;
}

}  // namespace lumistage
