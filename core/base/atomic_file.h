#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace lumistage {

// Reads a whole file; throws Error naming the file and the reason.
std::string readFile(const std::filesystem::path& path);

// Writes a file so that a crash or a full disk never leaves a torn one: the contents go to a
// temporary file beside it, are flushed to disk, and then renamed over the target. Throws Error
// naming the file and the reason; the old file, if any, is then untouched. `mode` is set before
// the rename, so a secret written with owner_read | owner_write is never readable by others.
void writeFileAtomically(const std::filesystem::path& path, std::string_view contents,
                         std::filesystem::perms mode = std::filesystem::perms::owner_read |
                                                       std::filesystem::perms::owner_write |
                                                       std::filesystem::perms::group_read |
                                                       std::filesystem::perms::others_read);

}  // namespace lumistage
