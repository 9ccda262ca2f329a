#include "app/cli/info_command.h"

#include <fmt/format.h>

#include "app/cli/machine_info.h"
#include "core/base/resource_path.h"

namespace lumistage {

void addInfoCommand(CLI::App& app) {
  CLI::App* info = app.add_subcommand(
      "info", "Print the version, the resource and shader folders in use, and the OpenGL device");
  info->callback([] {
    fmt::print("lumistage {}\n", LUMISTAGE_VERSION);
    // Each folder is found from a file every installation has.
    fmt::print("resources: {}\n",
               resourcePath("rigs/reference.yaml").parent_path().parent_path().string());
    fmt::print("shaders:   {}\n", shaderPath("studio_actor.vert").parent_path().string());
    const MachineInfo m = describeMachine();
    fmt::print("machine:   {}, {} threads, {:.1f} GiB\n", m.cpu, m.cores, m.memory_gib);
    fmt::print("OpenGL:    {}{}\n", m.opengl,
               m.opengl_software ? " (software rendering: no GPU in use)" : "");
  });
}

}  // namespace lumistage
