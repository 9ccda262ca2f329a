// lumistage: the command line of the studio (rig files now; run, record, replay, render,
// calibrate, synth, eval and bench join as they are built).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <exception>

#include "app/cli/body_commands.h"
#include "app/cli/calibrate_commands.h"
#include "app/cli/camera_commands.h"
#include "app/cli/corpus_command.h"
#include "app/cli/eval_command.h"
#include "app/cli/export_command.h"
#include "app/cli/info_command.h"
#include "app/cli/key_commands.h"
#include "app/cli/render_command.h"
#include "app/cli/rig_commands.h"
#include "app/cli/run_command.h"
#include "app/cli/session_commands.h"
#include "app/cli/synth_command.h"
#include "app/cli/video_commands.h"

int main(int argc, char** argv) {
  CLI::App app{"Lumistage: live free-viewpoint video of people from a calibrated camera stage"};
  app.set_version_flag("--version", LUMISTAGE_VERSION);
  app.set_help_all_flag("--help-all", "Print this help with every subcommand's options, and exit");
  app.require_subcommand(1);
  lumistage::addRigCommands(app);
  lumistage::addBodyCommands(app);
  lumistage::addCameraCommands(app);
  lumistage::addRunCommand(app);
  lumistage::addKeyCommands(app);
  lumistage::addSynthCommand(app);
  lumistage::addInfoCommand(app);
  lumistage::addCalibrateCommands(app);
  lumistage::addEvalCommand(app);
  lumistage::addCorpusCommand(app);
  lumistage::addExportCommand(app);
  lumistage::addRenderCommand(app);
  lumistage::addSessionCommands(app);
  lumistage::addVideoCommands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    fmt::print(stderr, "lumistage: error: {}\n", e.what());
    return 1;
  }
  return 0;
}
