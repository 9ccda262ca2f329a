#include "app/cli/machine_info.h"

#include <fmt/format.h>

#include <exception>
#include <fstream>
#include <thread>

#include "core/render/egl_context.h"

namespace lumistage {

namespace {

// The value after "key<spaces>:" of the first line of a /proc file that starts with `key`.
std::string procValue(const char* file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(key, 0) != 0) continue;
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    const size_t start = line.find_first_not_of(" \t", colon + 1);
    return start == std::string::npos ? "" : line.substr(start);
  }
  return "";
}

std::string jsonString(const std::string& s) {
  std::string out;
  for (char c : s) out += (c == '"' || c == '\\' || c < ' ') ? ' ' : c;
  return "\"" + out + "\"";
}

}  // namespace

MachineInfo describeMachine() {
  MachineInfo m;
  m.cpu = procValue("/proc/cpuinfo", "model name");
  if (m.cpu.empty()) m.cpu = "unknown CPU";
  m.cores = int(std::thread::hardware_concurrency());
  const std::string mem = procValue("/proc/meminfo", "MemTotal");  // "24576000 kB"
  if (!mem.empty()) m.memory_gib = std::stod(mem) / (1024.0 * 1024.0);
  try {
    const EglContext gl;
    m.opengl = gl.description();
    m.opengl_software = gl.isSoftware();
  } catch (const std::exception& e) {
    m.opengl = std::string("unavailable: ") + e.what();
  }
  return m;
}

std::string machineJson(const MachineInfo& m) {
  return fmt::format(
      "{{\"cpu\": {}, \"cores\": {}, \"memory_gib\": {:.1f}, \"opengl\": {}, "
      "\"opengl_software\": {}}}",
      jsonString(m.cpu), m.cores, m.memory_gib, jsonString(m.opengl),
      m.opengl_software ? "true" : "false");
}

}  // namespace lumistage
