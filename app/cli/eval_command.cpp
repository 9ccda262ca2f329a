#include "app/cli/eval_command.h"

#include <fmt/format.h>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/body/human_model.h"
#include "core/capture/session_reader.h"
#include "core/eval/eval_report.h"
#include "core/eval/mocap_eval.h"

namespace lumistage {

void addEvalCommand(CLI::App& app) {
  struct Args {
    std::string session, json;
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
    evaluateMocap(session, loadGenericHuman(), mocap, report);
    if (!args->json.empty()) writeFileAtomically(args->json, report.toJson());
    if (!args->quiet) fmt::print("{}", report.toText());
  });
}

}  // namespace lumistage
