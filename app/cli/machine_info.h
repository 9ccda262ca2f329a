#pragma once

#include <string>

namespace lumistage {

// The machine a figure was measured on, for reports and plots.
struct MachineInfo {
  std::string cpu;  // "AMD EPYC 7B13", from /proc/cpuinfo
  int cores = 0;    // hardware threads
  double memory_gib = 0;
  std::string opengl;  // the EGL device that renders, or why there is none
  bool opengl_software = true;
};

MachineInfo describeMachine();
// {"cpu": ..., "cores": ..., "memory_gib": ..., "opengl": ..., "opengl_software": ...}
std::string machineJson(const MachineInfo& machine);

}  // namespace lumistage
