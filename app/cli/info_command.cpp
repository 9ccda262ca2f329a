#include "app/cli/info_command.h"

#include <fmt/format.h>

#include "app/cli/machine_info.h"
#include "core/base/resource_path.h"
#include "core/capture/aravis_source.h"

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
    // For a camera PC: what the kernel lets a GigE Vision stream buffer, against the reference
    // camera's image (1024x768, one byte a pixel).
    const int64_t limit = receiveBufferLimit();
    constexpr int64_t kReferenceImage = 1024 * 768;
    if (limit >= 0) {
      const std::string advice = receiveBufferAdvice(limit, kReferenceImage);
      fmt::print("network:   net.core.rmem_max {} KB{}\n", limit / 1024,
                 advice.empty() ? " (room for GigE Vision streams of 1024x768 cameras)"
                                : "\n           " + advice);
    }
  });
}

}  // namespace lumistage
