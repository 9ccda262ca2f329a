#include "core/base/resource_path.h"

#include <cstdlib>
#include <string>
#include <system_error>
#include <vector>

#include "core/base/error.h"

namespace lumistage {

std::filesystem::path resourcePath(std::string_view relative) {
  namespace fs = std::filesystem;
  std::vector<fs::path> roots;
  if (const char* env = std::getenv("LUMISTAGE_RESOURCE_DIR"); env && *env) roots.emplace_back(env);
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) roots.push_back(exe.parent_path().parent_path() / "share" / "lumistage" / "resources");
  roots.emplace_back(LUMISTAGE_SOURCE_RESOURCE_DIR);

  std::string tried;
  for (const fs::path& root : roots) {
    fs::path candidate = root / relative;
    if (fs::exists(candidate, ec)) return candidate;
    tried += "\n  " + candidate.string();
  }
  throw Error("resource '" + std::string(relative) + "' not found; looked in:" + tried +
              "\n(set LUMISTAGE_RESOURCE_DIR to the resources/ folder of your installation)");
}

}  // namespace lumistage
