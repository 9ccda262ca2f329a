#include "core/base/error.h"

namespace lumistage {

std::string locate(std::string_view file, int line, std::string_view key,
                   std::string_view message) {
  std::string out;
  if (!file.empty()) {
    out += file;
    if (line > 0) out += ":" + std::to_string(line);
    out += ": ";
  }
  if (!key.empty()) {
    out += key;
    out += ": ";
  }
  out += message;
  return out;
}

}  // namespace lumistage
