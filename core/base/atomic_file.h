#pragma once

#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>

#include "core/base/status.h"

namespace lumistage {

// Reads a whole file; throws Error naming the file and the reason.
std::string readFile(const std::filesystem::path& path);

// Writes a file so that a crash or a full disk never leaves a torn one: the contents go to a
// temporary file beside it (`<name>.tmp-XXXXXX`), flushed to disk when `sync`, given its `mode`
// (so that a secret written owner-only is never readable by others), and renamed over the
// target. Throws Error naming the file and the reason ("disk full?" on ENOSPC/EFBIG); the old
// file, if any, is then untouched. Configuration files sync; recorded frames do not: a crash of
// the process is what they must survive, and an fsync per image would stall capture.
struct AtomicWriteOptions {
  bool sync = true;
  std::filesystem::perms mode =
      std::filesystem::perms::owner_read | std::filesystem::perms::owner_write |
      std::filesystem::perms::group_read | std::filesystem::perms::others_read;
};
void writeFileAtomically(const std::filesystem::path& path, std::string_view contents,
                         const AtomicWriteOptions& options = {});
// The same, the contents given in pieces (a header and the data it describes, not copied into one).
void writeFileAtomically(const std::filesystem::path& path,
                         std::initializer_list<std::string_view> pieces,
                         const AtomicWriteOptions& options = {});

// A file that grows by whole records (a session's index lines): each append() is written through
// to the file at once, all or nothing. A short or failed write is cut back to the last whole record
// and the file takes no more records: nothing left in a buffer can complete a torn line later (an
// std::ofstream retries its buffer when closed, once a full disk has room again). Not copyable.
class AppendOnlyFile {
 public:
  AppendOnlyFile() = default;
  AppendOnlyFile(const AppendOnlyFile&) = delete;
  AppendOnlyFile& operator=(const AppendOnlyFile&) = delete;
  ~AppendOnlyFile();
  // Creates or empties the file. Throws Error naming it and the reason.
  void create(const std::filesystem::path& path);
  // False (the file cut back to what it held before) on any failure, and ever after one.
  bool append(std::string_view record);
  bool failed() const { return failed_; }
  const std::filesystem::path& path() const { return path_; }
  Status status() const { return failed_ ? Status::failure(error_) : Status(); }

 private:
  std::filesystem::path path_;
  int fd_ = -1;
  int64_t length_ = 0;  // bytes of whole records
  bool failed_ = false;
  std::string error_;
};

// Whether a file name is a temporary of writeFileAtomically left by an interrupted write.
bool isAtomicWriteLeftover(std::string_view file_name);

}  // namespace lumistage
