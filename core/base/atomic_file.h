#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace lumistage {

// Reads a whole file; throws Error naming the file and the reason.
std::string readFile(const std::filesystem::path& path);

// Writes a file so that a crash or a full disk never leaves a torn one: the contents go to a
// temporary file beside it (`<name>.tmp-XXXXXX`), are flushed to disk when `sync` (configuration
// files: yes; recorded frames: no, a crash of the process is what they must survive, and fsync
// per image would stall capture), and are then renamed over the target. Throws Error naming the
// file and the reason ("disk full?" on ENOSPC/EFBIG); the old file, if any, is then untouched.
void writeFileAtomically(const std::filesystem::path& path, std::string_view contents,
                         bool sync = true);

// Whether a file name is a temporary of writeFileAtomically left by an interrupted write.
bool isAtomicWriteLeftover(std::string_view file_name);

}  // namespace lumistage
