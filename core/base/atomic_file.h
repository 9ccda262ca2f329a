#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace lumistage {

// Reads a whole file; throws Error naming the file and the reason.
std::string readFile(const std::filesystem::path& path);

// Writes a file so that a crash or a full disk never leaves a torn one: the contents go to a
// temporary file beside it, are flushed to disk, and then renamed over the target. Throws Error
// naming the file and the reason; the old file, if any, is then untouched.
void writeFileAtomically(const std::filesystem::path& path, std::string_view contents);

}  // namespace lumistage
