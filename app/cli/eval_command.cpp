#include "app/cli/eval_command.h"

#include <fmt/format.h>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/body/human_model.h"
#include "core/capture/session_reader.h"
#include "core/eval/eval_report.h"
#include "core/eval/mocap_eval.h"
#include "core/eval/surface_metrics.h"
#include "core/sim/studio_config.h"

namespace lumistage {

void addEvalCommand(CLI::App& app) {
  struct Args {
    std::string session, json, config;
    int cameras = 0, frames = 0;
    bool quiet = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* eval = app.add_subcommand(
      "eval", "measure the studio's stages against a session's ground truth (truth/)");
  eval->add_option("--session", args->session, "session folder (lumistage synth writes one)")
      ->required();
  eval->add_option("--json", args->json, "write the report as JSON (docs/eval-report.md)");
  eval->add_option("--cameras", args->cameras,
                   "use this many of the rig's cameras, evenly spread (default: all)");
  eval->add_option("--frames", args->frames, "only the first N frames (default: all)");
  eval->add_option("--config", args->config,
                   "studio config whose `refine:` section sets the refinement (default: built in)");
  eval->add_flag("--quiet", args->quiet, "no report on standard output");
  eval->callback([args] {
    const SessionReader session(args->session);
    if (!session.hasTruth())
      throw Error(args->session + ": no ground truth (truth/) to evaluate against");
    EvalReport report;
    report.setText("session", "session", args->session);
    // Stages add their sections in pipeline order; a later stage may use an earlier one's result.
    MocapEvalOptions mocap;
    mocap.camera_count = args->cameras;
    mocap.max_frames = args->frames;
    const SkinnedMesh generic = loadGenericHuman();
    evaluateMocap(session, generic, mocap, report);

    // Refinement: the generic human posed by a fit to the true joints, refined from the images,
    // both measured against the true surface.
    SurfaceEvaluationOptions surface;
    if (!args->config.empty()) surface.refine = loadStudioConfig(args->config).refine;
    surface.max_frames = args->frames;
    const SurfaceEvaluation e = evaluateSurface(args->session, generic, surface);
    report.set("refine", "surface_frames", e.frames);
    report.set("refine", "surface_mm_unrefined", e.unrefined.mean_mm);
    report.set("refine", "surface_mm_unrefined_p95", e.unrefined.p95_mm);
    report.set("refine", "surface_mm_refined", e.refined.mean_mm);
    report.set("refine", "surface_mm_refined_p95", e.refined.p95_mm);
    report.set("refine", "joint_fit_rms_mm", e.joint_fit_rms_mm);
    report.set("refine", "refine_offset_change_mm", e.offset_change_mm);
    report.set("refine", "refine_bytes_per_node_per_frame", e.statistics_bytes_per_node);
    for (size_t i = 0; i < e.refined_per_frame.size(); ++i) {
      const int64_t frame = surface.first_frame + int64_t(i) * surface.frame_step;
      report.setFrame(frame, "surface_mm_unrefined", e.unrefined_per_frame[i].mean_mm);
      report.setFrame(frame, "surface_mm_refined", e.refined_per_frame[i].mean_mm);
    }
    if (!args->json.empty()) writeFileAtomically(args->json, report.toJson());
    if (!args->quiet) fmt::print("{}", report.toText());
  });
}

}  // namespace lumistage
