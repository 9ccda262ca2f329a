#include "app/cli/session_commands.h"

#include <fmt/format.h>

#include <memory>

#include "app/cli/progress.h"
#include "core/capture/take_merge.h"
#include "core/geometry/rig_file.h"

namespace lumistage {

void addSessionCommands(CLI::App& app) {
  CLI::App* session = app.add_subcommand("session", "Work with recorded sessions and takes");
  session->require_subcommand(1);

  struct MergeArgs {
    std::vector<std::string> parts;
    std::string out, rig, image_files;
  };
  auto m = std::make_shared<MergeArgs>();
  CLI::App* merge = session->add_subcommand(
      "merge",
      "Join a take's parts (each node records its own cameras: TAKES/<take>/<node>/) into one "
      "session of every camera: the frames all parts hold");
  merge->add_option("parts", m->parts, "the take's folder, or its parts' folders")->required();
  merge->add_option("--out", m->out, "the merged session's folder (new or empty)")->required();
  merge->add_option("--rig", m->rig,
                    "order cameras and nodes as in this rig file (default: part after part)");
  merge
      ->add_option("--image-files", m->image_files,
                   "store the images as png (a third smaller: encoded again, 10 ms or more an "
                   "image) or pnm (default: as the parts, copied)")
      ->check(CLI::IsMember({"pnm", "png"}));
  merge->callback([m] {
    std::vector<std::filesystem::path> paths(m->parts.begin(), m->parts.end());
    const std::vector<std::filesystem::path> parts = takeParts(paths);
    std::optional<Rig> rig;
    if (!m->rig.empty()) rig = loadRig(m->rig);
    std::optional<ImageFiles> files;
    if (!m->image_files.empty()) files = parseImageFiles(m->image_files);
    const TakeMergeReport report = mergeTake(parts, m->out, rig, files, [](int done, int total) {
      printProgress("merging", done, total);
    });
    for (const std::string& note : report.notes) fmt::print("{}\n", note);
    fmt::print("merged {} parts: {} frame sets, {:.1f} MB, into {}\n", parts.size(), report.frames,
               report.bytes / 1e6, m->out);
  });
}

}  // namespace lumistage
