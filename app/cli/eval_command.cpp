#include "app/cli/eval_command.h"

#include <fmt/format.h>

#include <chrono>
#include <memory>

#include "core/base/atomic_file.h"
#include "core/body/human_model.h"
#include "core/eval/surface_metrics.h"
#include "core/sim/studio_config.h"

namespace lumistage {

void addEvalCommand(CLI::App& app) {
  struct Args {
    std::string session, json, config;
    int frames = 0, first = 0, step = 1;
  };
  auto args = std::make_shared<Args>();
  CLI::App* eval = app.add_subcommand(
      "eval", "Measure a virtual-studio session's reconstruction against its ground truth");
  eval->add_option("--session", args->session, "session folder (from lumistage synth)")->required();
  eval->add_option("--json", args->json, "write the figures to this JSON file");
  eval->add_option("--config", args->config,
                   "studio config whose `refine:` section sets the refinement (default: built in)");
  eval->add_option("--frames", args->frames, "evaluate at most this many frames (0: all)");
  eval->add_option("--first", args->first, "first frame to evaluate");
  eval->add_option("--step", args->step, "evaluate every step-th frame");
  eval->callback([args] {
    SurfaceEvaluationOptions options;
    if (!args->config.empty()) options.refine = loadStudioConfig(args->config).refine;
    options.max_frames = args->frames;
    options.first_frame = args->first;
    options.frame_step = args->step;
    const auto start = std::chrono::steady_clock::now();
    const SurfaceEvaluation e = evaluateSurface(args->session, loadGenericHuman(), options);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    fmt::print(
        "surface, {} frames (generic mesh posed by a fit to the true joints, rms {:.1f} mm):\n"
        "  unrefined: mean {:.1f} mm, p95 {:.1f} mm\n"
        "  refined:   mean {:.1f} mm, p95 {:.1f} mm ({:+.0f}%)\n"
        "  offsets change {:.2f} mm a vertex from frame to frame\n"
        "  refinement statistics: {:.0f} bytes per node per frame\n"
        "({:.1f} s)\n",
        e.frames, e.joint_fit_rms_mm, e.unrefined.mean_mm, e.unrefined.p95_mm, e.refined.mean_mm,
        e.refined.p95_mm, 100.0 * (e.refined.mean_mm / e.unrefined.mean_mm - 1.0),
        e.offset_change_mm, e.statistics_bytes_per_node, seconds);
    if (!args->json.empty()) {
      const std::string json = fmt::format(
          "{{\n  \"frames\": {},\n  \"surface_mm_unrefined\": {:.3f},\n"
          "  \"surface_mm_unrefined_p95\": {:.3f},\n  \"surface_mm_refined\": {:.3f},\n"
          "  \"surface_mm_refined_p95\": {:.3f},\n  \"joint_fit_rms_mm\": {:.3f},\n"
          "  \"refine_offset_change_mm\": {:.3f},\n"
          "  \"refine_bytes_per_node_per_frame\": {:.1f}\n}}\n",
          e.frames, e.unrefined.mean_mm, e.unrefined.p95_mm, e.refined.mean_mm, e.refined.p95_mm,
          e.joint_fit_rms_mm, e.offset_change_mm, e.statistics_bytes_per_node);
      writeFileAtomically(args->json, json);
    }
  });
}

}  // namespace lumistage
