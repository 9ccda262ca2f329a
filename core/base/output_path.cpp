#include "core/base/output_path.h"

#include <fmt/format.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>

#include "core/base/error.h"

namespace lumistage {

namespace fs = std::filesystem;

void refuseOutputOverInputs(std::string_view option, const fs::path& output,
                            std::initializer_list<CommandInput> inputs) {
  if (output.empty()) return;
  std::error_code error;
  fs::path out = fs::weakly_canonical(fs::absolute(output), error);
  if (error) return;  // a path the command's own open will name in its error
  if (!out.has_filename()) out = out.parent_path();
  for (const CommandInput& input : inputs) {
    if (input.path.empty()) continue;
    fs::path in = fs::weakly_canonical(fs::absolute(input.path), error);
    if (error) continue;
    if (!in.has_filename()) in = in.parent_path();  // "session/" as "session"
    const std::string what = std::string(option) + " " + output.string();
    const std::string of = std::string(input.option) + " " + input.path.string();
    if (out == in)
      throw Error(what + ": it is " + of + ", which the command reads; write it elsewhere");
    // Inside the input folder: every component of the input's path begins the output's.
    const auto [end_in, end_out] = std::mismatch(in.begin(), in.end(), out.begin(), out.end());
    if (end_in == in.end() && fs::is_directory(in, error))
      throw Error(what + ": inside " + of + ", which the command reads; write it elsewhere");
  }
}

void requireOutputFolder(std::string_view option, const fs::path& output) {
  if (output.empty()) return;
  const fs::path folder = fs::absolute(output).parent_path();
  std::error_code error;
  if (!fs::is_directory(folder, error))
    throw Error(std::string(option) + " " + output.string() + ": no folder " + folder.string() +
                " to write it into");
}

std::string lowercaseExtension(const std::filesystem::path& file) {
  std::string extension = file.extension().string();
  for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}

DiskSpace diskSpaceAt(const fs::path& path) {
  std::error_code error;
  fs::path at = fs::absolute(path, error);
  if (error) return {};
  for (;;) {
    struct statvfs disk {};
    if (::statvfs(at.c_str(), &disk) == 0) {
      char host[256] = {};
      ::gethostname(host, sizeof(host) - 1);
      return {int64_t(disk.f_bavail) * int64_t(disk.f_frsize),
              fmt::format("{}:{:x}", host, uint64_t(disk.f_fsid))};
    }
    if (!at.has_relative_path()) return {};  // not even the root
    at = at.parent_path();
  }
}

std::string bytesInWords(int64_t bytes) {
  const double b = double(bytes);
  if (b >= 1e12) return fmt::format("{:.2f} TB", b / 1e12);
  if (b >= 1e9) return fmt::format("{:.1f} GB", b / 1e9);
  if (b >= 1e6) return fmt::format("{:.0f} MB", b / 1e6);
  return fmt::format("{:.0f} kB", b / 1e3);
}

}  // namespace lumistage
