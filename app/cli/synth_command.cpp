#include "app/cli/synth_command.h"

#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <memory>

#include "app/cli/corpus_command.h"
#include "app/cli/progress.h"
#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/capture/session_writer.h"
#include "core/sim/stage_draw.h"
#include "core/sim/virtual_studio.h"

namespace lumistage {

namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace

void addSynthCommand(CLI::App& app) {
  struct Args {
    std::string config, out, sheet;
    int frames = 120;
    int plate_frames = -1;
    bool bayer = false;
    int64_t seed = -1;
    StageDrawOptions draw;
  };
  auto args = std::make_shared<Args>();
  CLI::App* synth = app.add_subcommand(
      "synth", "Film the virtual studio: write a session of images, rig and ground truth");
  CLI::Option* config = synth->add_option(
      "--config", args->config, "studio config (YAML), e.g. resources/studio/reference.yaml");
  CLI::Option* seed =
      synth
          ->add_option("--seed", args->seed,
                       "or a stage drawn at random from this seed (rig, actor, motion, look: the "
                       "corpus's; its config is written beside the session as studio.yaml)")
          ->check(CLI::Range(int64_t(0), int64_t(0xffffffff)));
  config->excludes(seed);
  addStageDrawOptions(*synth, args->draw);
  synth->add_option("--frames", args->frames, "number of frames")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  synth->add_option("-o,--out", args->out, "session folder to create (must not exist or be empty)")
      ->required();
  synth
      ->add_option("--plate-frames", args->plate_frames,
                   "frames of the empty stage to write as the session's plate (default: 10 when "
                   "the look's backdrop is a room, none on a green screen)")
      ->check(CLI::Range(0, 1000));
  synth->add_flag("--bayer", args->bayer, "store Bayer RGGB8 images, as GigE cameras deliver");
  synth->add_option("--contact-sheet", args->sheet,
                    "also write the middle frame's views, side by side, here (PNG)");
  synth->callback([args] {
    if (args->config.empty() == (args->seed < 0))
      throw Error("synth: give a studio config (--config) or a seed to draw a stage from (--seed)");
    args->draw.frames = args->frames;
    StudioConfig config = args->seed >= 0 ? drawStage(uint32_t(args->seed), args->draw)
                                          : loadStudioConfig(args->config);
    if (args->seed >= 0) fmt::print("stage {}: {}\n", args->seed, describeStage(config));
    if (args->bayer) config.pixel_format = PixelFormat::kBayerRggb8;
    const auto setup_start = Clock::now();
    VirtualStudio studio(std::move(config), args->frames);
    fmt::print(
        "virtual studio: {} cameras on {} nodes, actor of {} vertices, clip '{}' ({:.1f} s), "
        "rendering on {} "
        "({:.0f} ms to set up)\n",
        studio.rig().cameraCount(), studio.rig().nodeCount(), studio.actor().rest.vertexCount(),
        studio.clip().name, studio.clip().durationSeconds(), studio.rendererDescription(),
        millisecondsSince(setup_start));

    const std::unique_ptr<SessionWriter> writer = openStudioSession(studio, args->out);
    if (args->seed >= 0)
      writeFileAtomically(writer->folder() / "studio.yaml",
                          formatStudioConfig(studio.config(), "rig.yaml"));
    const bool room = studio.config().look.backdrop == StudioLook::Backdrop::kRoom;
    const int plate_frames = args->plate_frames >= 0 ? args->plate_frames : room ? 10 : 0;
    if (plate_frames > 0) {
      writeStudioPlate(studio, plate_frames, *writer);
      fmt::print("wrote {} frames of the empty stage as the plate\n", plate_frames);
    }
    StudioFrame frame;
    std::vector<Image> images;
    double render_ms = 0, write_ms = 0;
    const auto start = Clock::now();
    for (int f = 0; f < args->frames; ++f) {
      auto t0 = Clock::now();
      studio.renderFrame(f, frame);
      render_ms += millisecondsSince(t0);
      t0 = Clock::now();
      writeStudioFrame(studio, frame, f, *writer, images);
      write_ms += millisecondsSince(t0);
      if (f == args->frames / 2) {  // mid-motion: more telling than the T-pose of frame 0
        writeContactSheet(studio.rig(), frame, writer->folder() / "contact_sheet.png");
        if (!args->sheet.empty()) writeContactSheet(studio.rig(), frame, args->sheet);
      }
      printProgress("synth", f + 1, args->frames, millisecondsSince(start) / (f + 1));
    }
    fmt::print(
        "wrote {} frames to {}: {:.1f} ms a frame to pose and render {} views, {:.1f} ms to write "
        "them\n",
        args->frames, args->out, render_ms / args->frames, studio.rig().cameraCount(),
        write_ms / args->frames);
  });
}

}  // namespace lumistage
