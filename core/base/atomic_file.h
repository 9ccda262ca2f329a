#pragma once

#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>

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

// Whether a file name is a temporary of writeFileAtomically left by an interrupted write.
bool isAtomicWriteLeftover(std::string_view file_name);

}  // namespace lumistage
