// lumistage-studio: the Qt6 coordinator of the stage.
#include <QApplication>
#include <QCommandLineParser>
#include <QMessageBox>
#include <QSocketNotifier>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <optional>

#include "core/base/resource_path.h"
#include "core/base/stop_signal.h"
#include "core/body/human_model.h"
#include "ui/main_window.h"
#include "ui/pipeline_panel.h"
#include "ui/source_worker.h"
#include "ui/studio_screenshots.h"

namespace {

// Qt aborts with a terse message when it cannot reach a display; say what to do instead.
bool haveDisplay(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::string_view(argv[i]) == "-platform") return true;
  }
  auto set = [](const char* name) {
    const char* value = std::getenv(name);
    return value && *value;
  };
  return set("DISPLAY") || set("WAYLAND_DISPLAY") || set("QT_QPA_PLATFORM");
}

// Whether the command line asks for help: answered without a display.
bool asksForHelp(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string_view a(argv[i]);
    if (a == "-h" || a == "--help" || a == "--help-all") return true;
  }
  return false;
}

// The studio's command line: its options, declared and parsed.
struct CommandLine {
  QCommandLineOption rig{
      "rig", "Rig file to open (default: the reference rig; with aravis, the cameras' rig).",
      "file"};
  QCommandLineOption source{"source",
                            "Where frames come from: virtual[:STUDIO_CONFIG] (default, the "
                            "reference virtual studio), session:DIR "
                            "(a recording, looped at its rate), aravis[:FIRST_ADDRESS] "
                            "(GigE Vision cameras, camera i at address+i), "
                            "none.",
                            "source", "virtual"};
  QCommandLineOption screenshot{
      "screenshot",
      "Save a screenshot of the main window to <png> once every camera shows a picture (and a "
      "pipeline started with the studio has shown frames), then quit.",
      "png"};
  QCommandLineOption pipeline{
      "pipeline",
      "Also run the distributed pipeline on a recorded session: a node process per rig node.",
      "session"};
  QCommandLineOption listen{
      "listen",
      "Run the distributed pipeline with the nodes on the stage's PCs (lumistage-node --studio, "
      "or their systemd unit): listen for them at <endpoint> (e.g. tcp://*:5570), with --rig and "
      "--keys.",
      "endpoint"};
  QCommandLineOption keys{
      "keys", "With --listen: the key store the nodes were given (lumistage keys init).", "dir"};
  QCommandLineOption plain{
      "plain",
      "With --listen: plain TCP, neither encrypted nor authenticated, for a closed lab network "
      "only; the nodes must be started with --plain too."};
  QCommandLineOption body{
      "body",
      "The body the pipeline poses and refines: standard (about 2000 vertices: four nodes and "
      "the studio on one PC), fine (about 4000: sharper views, twice the nodes' work; nodes on "
      "PCs of their own, each started with --body fine), or a rigged human's file (glTF/GLB, "
      "FBX, COLLADA, X; nodes on the stage's PCs started with --body FILE). Remembered between "
      "runs.",
      "body"};
  QCommandLineOption demo{
      "demo",
      "The demo: film the virtual studio once (a short session, kept in the cache folder), replay "
      "it as the cameras and run the distributed pipeline on it, every panel alive."};
  QCommandLineOption screenshots{
      "screenshots",
      "With --demo: once the pipeline has shown frames, save the main window and each panel to "
      "<dir> (main_window.png, viewport.png, viewport_behind.png, health.png, overlay.png, "
      "calibration.png, clones.png, pipeline.png while the nodes record a take into <dir>/takes; "
      "the "
      "view from behind is recorded meanwhile to viewport_behind.avi), kill a node and save "
      "health_node_lost.png once its cameras show "
      "lost, then quit.",
      "dir"};
  QCommandLineParser parser;

  explicit CommandLine(const QApplication& app) {
    parser.setApplicationDescription("Lumistage Studio: live free-viewpoint video of people");
    parser.addHelpOption();
    parser.addOption(demo);
    parser.addOption(screenshots);
    parser.addOption(rig);
    parser.addOption(source);
    parser.addOption(pipeline);
    parser.addOption(listen);
    parser.addOption(keys);
    parser.addOption(plain);
    parser.addOption(body);
    parser.addOption(screenshot);
    parser.process(app);
  }
  bool isSet(const QCommandLineOption& option) const { return parser.isSet(option); }
  QString value(const QCommandLineOption& option) const { return parser.value(option); }
};

}  // namespace

int main(int argc, char** argv) {
  if (asksForHelp(argc, argv)) setenv("QT_QPA_PLATFORM", "offscreen", 1);
  if (!haveDisplay(argc, argv)) {
    std::fprintf(stderr,
                 "lumistage-studio: no display: neither DISPLAY nor WAYLAND_DISPLAY is set.\n"
                 "Run it on a desktop, over 'ssh -X', or under a virtual display: "
                 "xvfb-run -a ./studio demo\n");
    return 2;
  }
  QApplication app(argc, argv);
  QApplication::setApplicationName("Lumistage Studio");
  QApplication::setOrganizationName("Lumistage");

  const CommandLine line(app);
  if (int(line.isSet(line.pipeline)) + int(line.isSet(line.listen)) + int(line.isSet(line.demo)) >
      1) {
    // One pipeline at a time: each started the pipeline panel, the last replacing the others.
    std::fprintf(stderr,
                 "lumistage-studio: give one of --demo, --pipeline SESSION and --listen ADDRESS\n");
    return 2;
  }

  QString rig_path = line.value(line.rig);
  if (rig_path.isEmpty()) {
    try {
      rig_path = QString::fromStdString(lumistage::resourcePath("rigs/reference.yaml").string());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "lumistage-studio: %s\n", e.what());
    }
  }

  std::optional<lumistage::BodyChoice> body;
  if (line.isSet(line.body)) {
    try {
      body = lumistage::parseBodyChoice(line.value(line.body).toStdString());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "lumistage-studio: --body: %s\n", e.what());
      return 2;
    }
  }

  lumistage::MainWindow window;
  if (body && !body->file.empty()) {
    // Read before the window shows, as the choice's "Body file..." reads it.
    const lumistage::Status chosen =
        window.pipeline()->chooseBodyFile(QString::fromStdString(body->file.string()));
    if (!chosen.ok()) {
      std::fprintf(stderr, "lumistage-studio: --body: %s\n", chosen.error().c_str());
      return 2;
    }
  } else if (body) {
    window.pipeline()->setBody(*body);
  }
  window.show();
  // Ctrl-C in its terminal, SIGTERM (a logout, a service manager) or SIGHUP closes the studio as
  // its close button does: a recording of the view finished, the nodes it started stopped after
  // closing their take, its temporary keys removed. A second one ends it at once.
  lumistage::stopOnSignals();
  if (const int fd = lumistage::stopSignalDescriptor(); fd >= 0) {
    auto* notifier = new QSocketNotifier(fd, QSocketNotifier::Read, &app);
    QObject::connect(notifier, &QSocketNotifier::activated, &app, [notifier, &window] {
      notifier->setEnabled(false);
      std::fprintf(stderr, "lumistage-studio: stopped by %s; closing\n",
                   lumistage::stopSignalName(lumistage::stopSignal()));
      window.closeWithoutAsking();
      QApplication::quit();
    });
  }
  if (!rig_path.isEmpty()) {
    if (const QString error = window.openRig(rig_path); !error.isEmpty()) {
      std::fprintf(stderr, "lumistage-studio: %s\n", qPrintable(error));
      if (!line.isSet(line.screenshot)) QMessageBox::warning(&window, "Cannot open rig", error);
    }
  }
  const QString source = line.value(line.source);
  // The screenshots' take goes beside them, not into the user's takes.
  if (line.isSet(line.screenshots))
    window.pipeline()->setTakesFolder(line.value(line.screenshots) + "/takes");
  if (line.isSet(line.demo)) {
    QObject::connect(&window, &lumistage::MainWindow::demoFailed, &app, [&](const QString& error) {
      std::fprintf(stderr, "lumistage-studio: demo: %s\n", qPrintable(error));
      if (line.isSet(line.screenshots)) QApplication::exit(1);
    });
    window.startDemo();
  } else if (source != "none") {
    lumistage::SourceSpec spec;
    if (const QString error = lumistage::SourceSpec::parse(source, spec); !error.isEmpty()) {
      std::fprintf(stderr, "lumistage-studio: %s\n", qPrintable(error));
      return 2;
    }
    spec.rig = line.value(line.rig);
    window.startSource(spec);
  }
  if (line.isSet(line.listen)) {
    lumistage::LocalRunOptions options;
    options.rig = rig_path.toStdString();
    options.keys = line.value(line.keys).toStdString();
    options.listen = line.value(line.listen).toStdString();
    options.plain = line.isSet(line.plain);
    window.pipeline()->start(options);
    window.showPipeline();
  }
  if (line.isSet(line.pipeline)) {
    lumistage::LocalRunOptions options;
    options.session = line.value(line.pipeline).toStdString();
    options.replay = "memory";
    window.pipeline()->start(options);
    window.showPipeline();
  }
  if (line.isSet(line.screenshots))
    lumistage::startDemoScreenshots(window, line.value(line.screenshots));
  if (line.isSet(line.screenshot))
    lumistage::startScreenshotWhenReady(window, line.value(line.screenshot), source);
  return app.exec();
}
