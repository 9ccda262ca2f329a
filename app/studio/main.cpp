// lumistage-studio: the Qt6 coordinator of the stage.
#include <QApplication>
#include <QCommandLineParser>
#include <QMessageBox>
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "core/base/resource_path.h"
#include "ui/main_window.h"

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
  QCommandLineOption rig_option("rig", "Rig file to open (default: the reference rig).", "file");
  QCommandLineOption screenshot_option(
      "screenshot", "Save a screenshot of the main window to <png> once it is shown, then quit.",
      "png");
  parser.addOption(rig_option);
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
  if (parser.isSet(screenshot_option)) {
    const QString png = parser.value(screenshot_option);
    QMetaObject::invokeMethod(
        &window,
        [&window, png] {
          const bool ok = window.grab().save(png);
          std::fprintf(ok ? stdout : stderr, "%s %s\n", ok ? "saved" : "cannot save",
                       qPrintable(png));
          QApplication::exit(ok ? 0 : 1);
        },
        Qt::QueuedConnection);
  }
  return app.exec();
}
