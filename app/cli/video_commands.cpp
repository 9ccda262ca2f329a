#include "app/cli/video_commands.h"

#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <string>

#include "core/base/output_path.h"
#include "core/render/view_recorder.h"

namespace lumistage {

void addVideoCommands(CLI::App& app) {
  CLI::App* video = app.add_subcommand("video", "Work with the recordings of the view");
  video->require_subcommand(1);

  struct RecoverArgs {
    std::string partial, out;
  };
  auto a = std::make_shared<RecoverArgs>();
  CLI::App* recover = video->add_subcommand(
      "recover",
      "Make a whole video of a recording of the view that never closed (NAME.partial.avi or "
      ".mp4, left when the studio or lumistage run was killed, crashed or lost power): its whole "
      "frames (an MP4's whole seconds), copied as they are");
  recover
      ->add_option("partial", a->partial,
                   "the recording left behind: NAME.partial.avi or NAME.partial.mp4")
      ->required();
  recover->add_option(
      "--out", a->out,
      "the video to write, of the same kind (default: NAME-recovered.avi or .mp4, or "
      "-recovered-2... where that exists)");
  recover->callback([a] {
    const std::filesystem::path out =
        a->out.empty() ? recoveredVideoPath(a->partial) : std::filesystem::path(a->out);
    const std::string kind = lowercaseExtension(a->partial);
    if (lowercaseExtension(out) != kind)
      throw CLI::ValidationError("--out", out.string() +
                                              ": the video is of the recording's kind: "
                                              "name it " +
                                              kind);
    refuseOutputOverInputs("--out", out, {{"partial", a->partial}});
    requireOutputFolder("--out", out);
    const RecoveredVideo r = recoverPartialVideo(a->partial, out);
    fmt::print("recovered {} frames ({:.1f} s at {:g} fps) into {}{}\n", r.frames,
               r.fps > 0 ? r.frames / r.fps : 0.0, r.fps, out.string(),
               r.bytes_cut > 0
                   ? fmt::format("; the last {} bytes, a frame cut short, left out", r.bytes_cut)
                   : "");
  });
}

}  // namespace lumistage
