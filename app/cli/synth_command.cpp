#include "app/cli/synth_command.h"

#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

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

// All views of a frame in a grid, a quarter of their size, each labelled with its camera.
cv::Mat contactSheet(const Rig& rig, const StudioFrame& frame) {
  const int columns = rig.cameraCount() <= 4 ? rig.cameraCount() : 4;
  const int rows = (rig.cameraCount() + columns - 1) / columns;
  const int w = rig.camera(0).width() / 4, h = rig.camera(0).height() / 4;
  cv::Mat sheet(rows * (h + 4) + 4, columns * (w + 4) + 4, CV_8UC3, cv::Scalar(40, 40, 40));
  for (int c = 0; c < rig.cameraCount(); ++c) {
    const Camera& camera = rig.camera(c);
    const cv::Mat rgba(camera.height(), camera.width(), CV_8UC4,
                       const_cast<uint8_t*>(frame.images[c].data()));
    cv::Mat bgr, small;
    cv::cvtColor(rgba, bgr, cv::COLOR_RGBA2BGR);
    cv::resize(bgr, small, cv::Size(w, h), 0, 0, cv::INTER_AREA);
    const cv::Rect cell(4 + (c % columns) * (w + 4), 4 + (c / columns) * (h + 4), w, h);
    small.copyTo(sheet(cell));
    cv::putText(sheet, camera.name() + " (" + camera.node() + ")", cell.tl() + cv::Point(6, 18),
                cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  }
  return sheet;
}

}  // namespace

void addSynthCommand(CLI::App& app) {
  struct Args {
    std::string config, out, sheet;
    int frames = 120;
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
        const cv::Mat sheet = contactSheet(studio.rig(), frame);
        cv::imwrite((writer->folder() / "contact_sheet.png").string(), sheet);
        if (!args->sheet.empty() && !cv::imwrite(args->sheet, sheet)) {
          throw Error(args->sheet + ": cannot write the contact sheet");
        }
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
