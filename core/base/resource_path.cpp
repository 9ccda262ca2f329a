#include "core/base/resource_path.h"

#include <cstdlib>
#include <string>
#include <system_error>
#include <vector>

#include "core/base/error.h"

namespace lumistage {

namespace {

std::filesystem::path findData(std::string_view relative, const char* env_name,
                               const char* installed, const char* source_dir, const char* what) {
  namespace fs = std::filesystem;
  std::vector<fs::path> roots;
  if (const char* env = std::getenv(env_name); env && *env) roots.emplace_back(env);
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) roots.push_back(exe.parent_path().parent_path() / "share" / "lumistage" / installed);
  roots.emplace_back(source_dir);

  std::string tried;
  for (const fs::path& root : roots) {
    fs::path candidate = root / relative;
    if (fs::exists(candidate, ec)) return candidate;
    tried += "\n  " + candidate.string();
  }
  throw Error(std::string(what) + " '" + std::string(relative) + "' not found; looked in:" + tried +
              "\n(set " + env_name + " to the " + installed + "/ folder of your installation)");
}

}  // namespace

std::filesystem::path resourcePath(std::string_view relative) {
  return findData(relative, "LUMISTAGE_RESOURCE_DIR", "resources", LUMISTAGE_SOURCE_RESOURCE_DIR,
                  "resource");
}

std::filesystem::path shaderPath(std::string_view relative) {
  return findData(relative, "LUMISTAGE_SHADER_DIR", "shaders", LUMISTAGE_SOURCE_SHADER_DIR,
                  "shader");
}

}  // namespace lumistage
