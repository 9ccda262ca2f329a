// lumistage-studio: the Qt6 coordinator of the stage.
#include <QApplication>
#include <QCommandLineParser>
#include <QElapsedTimer>
#include <QMessageBox>
#include <QTimer>
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "core/base/resource_path.h"
#include "ui/camera_grid_panel.h"
#include "ui/main_window.h"
#include "ui/pipeline_panel.h"
#include "ui/source_worker.h"

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

}  // namespace

int main(int argc, char** argv) {
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

  QCommandLineParser parser;
  parser.setApplicationDescription("Lumistage Studio: live free-viewpoint video of people");
  parser.addHelpOption();
  QCommandLineOption rig_option(
      "rig", "Rig file to open (default: the reference rig; with aravis, the cameras' rig).",
      "file");
  QCommandLineOption source_option("source",
                                   "Where frames come from: virtual[:STUDIO_CONFIG] (default, the "
                                   "reference virtual studio), session:DIR "
                                   "(a recording, looped at its rate), aravis[:FIRST_ADDRESS] "
                                   "(GigE Vision cameras, camera i at address+i), "
                                   "none.",
                                   "source", "virtual");
  QCommandLineOption screenshot_option(
      "screenshot",
      "Save a screenshot of the main window to <png> once every camera shows a picture, then quit.",
      "png");
  QCommandLineOption pipeline_option(
      "pipeline",
      "Also run the distributed pipeline on a recorded session: a node process per rig node.",
      "session");
  parser.addOption(rig_option);
  parser.addOption(source_option);
  parser.addOption(pipeline_option);
  parser.addOption(screenshot_option);
  parser.process(app);

  QString rig_path = parser.value(rig_option);
  if (rig_path.isEmpty()) {
    try {
      rig_path = QString::fromStdString(lumistage::resourcePath("rigs/reference.yaml").string());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "lumistage-studio: %s\n", e.what());
    }
  }

  lumistage::MainWindow window;
  window.show();
  if (!rig_path.isEmpty()) {
    if (const QString error = window.openRig(rig_path); !error.isEmpty()) {
      std::fprintf(stderr, "lumistage-studio: %s\n", qPrintable(error));
      if (!parser.isSet(screenshot_option)) QMessageBox::warning(&window, "Cannot open rig", error);
    }
  }
  const QString source = parser.value(source_option);
  if (source != "none") {
    lumistage::SourceSpec spec;
    if (const QString error = lumistage::SourceSpec::parse(source, spec); !error.isEmpty()) {
      std::fprintf(stderr, "lumistage-studio: %s\n", qPrintable(error));
      return 2;
    }
    spec.rig = parser.value(rig_option);
    window.startSource(spec);
  }
  if (parser.isSet(pipeline_option)) {
    lumistage::LocalRunOptions options;
    options.session = parser.value(pipeline_option).toStdString();
    options.replay = "memory";
    window.pipeline()->start(options);
    window.showPipeline();
  }
  if (parser.isSet(screenshot_option)) {
    // Once every camera has shown pictures and counters for a few seconds (or after a minute; at
    // once without a source).
    const QString png = parser.value(screenshot_option);
    QObject::connect(&window, &lumistage::MainWindow::sourceFailed, &app, [](const QString& error) {
      std::fprintf(stderr, "lumistage-studio: %s\n", qPrintable(error));
      QApplication::exit(1);
    });
    auto* timer = new QTimer(&window);
    QElapsedTimer clock;
    clock.start();
    QObject::connect(timer, &QTimer::timeout, &window, [&window, png, clock, source, timer] {
      const auto* grid = window.cameraGrid();
      const bool ready = source == "none" || (grid->cameraCount() > 0 &&
                                              grid->camerasWithPictures() == grid->cameraCount() &&
                                              clock.elapsed() > 5000);
      if (!ready && clock.elapsed() < 60000) return;
      timer->stop();
      const bool ok = window.grab().save(png);
      std::fprintf(ok ? stdout : stderr, "%s %s%s\n", ok ? "saved" : "cannot save", qPrintable(png),
                   ready ? "" : " (not every camera had a picture after a minute)");
      QApplication::exit(ok && ready ? 0 : 1);
    });
    timer->start(300);
  }
  return app.exec();
}
