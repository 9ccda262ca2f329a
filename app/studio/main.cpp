// lumistage-studio: the Qt6 coordinator of the stage.
#include <QApplication>
#include <QCommandLineParser>
#include <QDir>
#include <QElapsedTimer>
#include <QMessageBox>
#include <QSocketNotifier>
#include <QTimer>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <functional>
#include <optional>

#include "core/base/resource_path.h"
#include "core/base/stop_signal.h"
#include "core/body/human_model.h"
#include "ui/calibration_panel.h"
#include "ui/camera_grid_panel.h"
#include "ui/clone_panel.h"
#include "ui/health_panel.h"
#include "ui/main_window.h"
#include "ui/overlay_panel.h"
#include "ui/pipeline_panel.h"
#include "ui/source_worker.h"
#include "ui/viewport_panel.h"

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
      "Save a screenshot of the main window to <png> once every camera shows a picture (and a "
      "pipeline started with the studio has shown frames), then quit.",
      "png");
  QCommandLineOption pipeline_option(
      "pipeline",
      "Also run the distributed pipeline on a recorded session: a node process per rig node.",
      "session");
  QCommandLineOption listen_option(
      "listen",
      "Run the distributed pipeline with the nodes on the stage's PCs (lumistage-node --studio, "
      "or their systemd unit): listen for them at <endpoint> (e.g. tcp://*:5570), with --rig and "
      "--keys.",
      "endpoint");
  QCommandLineOption keys_option(
      "keys", "With --listen: the key store the nodes were given (lumistage keys init).", "dir");
  QCommandLineOption plain_option(
      "plain",
      "With --listen: plain TCP, neither encrypted nor authenticated, for a closed lab network "
      "only; the nodes must be started with --plain too.");
  QCommandLineOption body_option(
      "body",
      "The generic human the pipeline poses and refines: standard (about 2000 vertices: four "
      "nodes and the studio on one PC) or fine (about 4000: sharper views, twice the nodes' work; "
      "nodes on PCs of their own, each started with --body fine). Remembered between runs.",
      "detail");
  QCommandLineOption demo_option(
      "demo",
      "The demo: film the virtual studio once (a short session, kept in the cache folder), replay "
      "it as the cameras and run the distributed pipeline on it, every panel alive.");
  QCommandLineOption screenshots_option(
      "screenshots",
      "With --demo: once the pipeline has shown frames, save the main window and each panel to "
      "<dir> (main_window.png, viewport.png, viewport_behind.png, health.png, overlay.png, "
      "calibration.png, clones.png, pipeline.png while the nodes record a take into <dir>/takes; "
      "the "
      "view from behind is recorded meanwhile to viewport_behind.avi), kill a node and save "
      "health_node_lost.png once its cameras show "
      "lost, then quit.",
      "dir");
  parser.addOption(demo_option);
  parser.addOption(screenshots_option);
  parser.addOption(rig_option);
  parser.addOption(source_option);
  parser.addOption(pipeline_option);
  parser.addOption(listen_option);
  parser.addOption(keys_option);
  parser.addOption(plain_option);
  parser.addOption(body_option);
  parser.addOption(screenshot_option);
  parser.process(app);
  if (int(parser.isSet(pipeline_option)) + int(parser.isSet(listen_option)) +
          int(parser.isSet(demo_option)) >
      1) {
    // One pipeline at a time: each started the pipeline panel, the last replacing the others.
    std::fprintf(stderr,
                 "lumistage-studio: give one of --demo, --pipeline SESSION and --listen ADDRESS\n");
    return 2;
  }

  QString rig_path = parser.value(rig_option);
  if (rig_path.isEmpty()) {
    try {
      rig_path = QString::fromStdString(lumistage::resourcePath("rigs/reference.yaml").string());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "lumistage-studio: %s\n", e.what());
    }
  }

  std::optional<lumistage::BodyDetail> body;
  if (parser.isSet(body_option)) {
    try {
      body = lumistage::parseBodyDetail(parser.value(body_option).toStdString());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "lumistage-studio: --body: %s\n", e.what());
      return 2;
    }
  }

  lumistage::MainWindow window;
  if (body) window.pipeline()->setBody(*body);
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
      if (!parser.isSet(screenshot_option)) QMessageBox::warning(&window, "Cannot open rig", error);
    }
  }
  const QString source = parser.value(source_option);
  // The screenshots' take goes beside them, not into the user's takes.
  if (parser.isSet(screenshots_option))
    window.pipeline()->setTakesFolder(parser.value(screenshots_option) + "/takes");
  if (parser.isSet(demo_option)) {
    QObject::connect(&window, &lumistage::MainWindow::demoFailed, &app, [&](const QString& error) {
      std::fprintf(stderr, "lumistage-studio: demo: %s\n", qPrintable(error));
      if (parser.isSet(screenshots_option)) QApplication::exit(1);
    });
    window.startDemo();
  } else if (source != "none") {
    lumistage::SourceSpec spec;
    if (const QString error = lumistage::SourceSpec::parse(source, spec); !error.isEmpty()) {
      std::fprintf(stderr, "lumistage-studio: %s\n", qPrintable(error));
      return 2;
    }
    spec.rig = parser.value(rig_option);
    window.startSource(spec);
  }
  if (parser.isSet(listen_option)) {
    lumistage::LocalRunOptions options;
    options.rig = rig_path.toStdString();
    options.keys = parser.value(keys_option).toStdString();
    options.listen = parser.value(listen_option).toStdString();
    options.plain = parser.isSet(plain_option);
    window.pipeline()->start(options);
    window.showPipeline();
  }
  if (parser.isSet(pipeline_option)) {
    lumistage::LocalRunOptions options;
    options.session = parser.value(pipeline_option).toStdString();
    options.replay = "memory";
    window.pipeline()->start(options);
    window.showPipeline();
  }
  if (parser.isSet(screenshots_option)) {
    const QString dir = parser.value(screenshots_option);
    QDir().mkpath(dir);
    window.resize(1600, 1000);
    window.resetLayout();  // the default layout, whatever was remembered
    // Steps a few hundred milliseconds apart, so that each panel is painted before it is grabbed.
    auto steps = std::make_shared<std::vector<std::function<bool()>>>();
    auto save = [&window, dir](const QString& panel, const QString& file) {
      return [&window, dir, panel, file] {
        QWidget* widget = panel.isEmpty() ? &window : window.showPanel(panel);
        const bool ok = widget && widget->grab().save(dir + "/" + file);
        std::fprintf(ok ? stdout : stderr, "%s %s/%s\n", ok ? "saved" : "cannot save",
                     qPrintable(dir), qPrintable(file));
        return true;
      };
    };
    auto* pipeline = window.pipeline();
    QElapsedTimer clock;
    clock.start();
    // Wait for the pipeline's frames with the placed body and every camera's picture.
    steps->push_back([&window, pipeline, clock] {
      const bool ready =
          pipeline->lastReport().frames >= 20 && pipeline->lastSnapshot().pose_frame >= 0 &&
          !pipeline->lastSnapshot().view.isNull() && window.cameraGrid()->cameraCount() > 0 &&
          window.cameraGrid()->camerasWithPictures() == window.cameraGrid()->cameraCount();
      if (!ready && clock.elapsed() > 240000) {
        std::fprintf(stderr, "lumistage-studio: no pipeline frames after 4 minutes\n");
        QApplication::exit(1);
      }
      return ready;
    });
    steps->push_back([&window] {
      window.showPanel("viewport");
      window.showPanel("overlay");
      window.showPanel("pipeline");
      return true;
    });
    steps->push_back(save("", "main_window.png"));
    steps->push_back(save("viewport", "viewport.png"));
    steps->push_back(save("health", "health.png"));
    steps->push_back([&window] {
      window.overlay()->selectCamera(2);  // cam03 sees the actor's side: the arms spread
      return true;
    });
    steps->push_back(save("overlay", "overlay.png"));
    // A take: every node records its cameras; the panel shows it recording.
    steps->push_back([pipeline] { return pipeline->startTake("take-001"); });
    steps->push_back([pipeline] {
      int recording = 0;
      for (const lumistage::NodeReport& n : pipeline->lastReport().nodes)
        recording += n.take.take == "take-001" && n.take.written >= 10;
      return recording == static_cast<int>(pipeline->lastReport().nodes.size());
    });
    steps->push_back(save("pipeline", "pipeline.png"));
    steps->push_back([pipeline] {
      pipeline->stopTake();
      return true;
    });
    steps->push_back([&window] {
      // A point on the chest (spine3) in the first camera: its epipolar lines in the others.
      auto* cal = window.calibration();
      const lumistage::Rig* rig = window.rig();
      if (rig && rig->cameraCount() > 1) {
        const auto& snap = window.pipeline()->lastSnapshot();
        const Eigen::Vector3d chest =
            snap.joints.size() > 3 ? snap.joints[3] : Eigen::Vector3d(0, 0, 1.3);
        if (const auto p = rig->camera(0).project(chest)) cal->pickPoint(0, *p);
      }
      return true;
    });
    steps->push_back(save("calibration", "calibration.png"));
    steps->push_back([&window] {
      // Two clones, the view from behind the actor (a half turn from the default).
      window.showPanel("clones");
      window.clonePanel()->addClone();
      window.clonePanel()->addClone();
      window.clonePanel()->turnSelected(3.14159265 / 2);
      window.showPanel("viewport");
      return true;
    });
    steps->push_back(save("clones", "clones.png"));
    steps->push_back([&window, dir] {
      lumistage::OrbitView view = lumistage::OrbitView::studioDefault();
      view.orbit(3.14159265, 0);
      window.viewport()->viewport()->setView(view);
      // Recording the director's view meanwhile: the viewport shows it (REC, frames so far).
      window.viewport()->record(true, dir + "/viewport_behind.avi");
      return true;
    });
    // The nodes render the new view: wait for a frame of it.
    auto turned_at = std::make_shared<int64_t>(-1);
    steps->push_back([pipeline, turned_at] {
      if (*turned_at < 0) *turned_at = pipeline->lastReport().frames;
      return pipeline->lastReport().frames > *turned_at + 10;
    });
    steps->push_back(save("viewport", "viewport_behind.png"));
    steps->push_back([&window] {
      window.viewport()->record(false);
      return true;
    });
    // A technician's check: kill a node and time how long its cameras take to show "lost".
    auto killed = std::make_shared<QElapsedTimer>();
    auto shown_after_ms = std::make_shared<qint64>(-1);
    steps->push_back([&window, killed, shown_after_ms] {
      window.showPanel("health");
      // When the health panel (connected before this) first says "lost" for node2's cameras.
      QObject::connect(window.pipeline(), &lumistage::PipelinePanel::snapshot, &window,
                       [killed, shown_after_ms](const lumistage::PipelineSnapshot& s) {
                         if (*shown_after_ms < 0 && killed->isValid() && s.exited.contains("node2"))
                           *shown_after_ms = killed->elapsed();
                       });
      window.pipeline()->killNode("node2");
      killed->start();
      return true;
    });
    steps->push_back([&window, killed, shown_after_ms] {
      auto* health = window.health();
      const lumistage::Rig* rig = window.rig();
      int camera = -1;
      for (int c = 0; rig && c < rig->cameraCount(); ++c) {
        if (rig->camera(c).node() == "node2") camera = c;
      }
      if (camera < 0) return true;
      if (health->verdict(camera).state != lumistage::HealthState::kLost) return false;
      std::printf(
          "node2 killed: the health panel had it lost after %lld ms (seen by this check after "
          "%lld ms)\n",
          static_cast<long long>(*shown_after_ms), static_cast<long long>(killed->elapsed()));
      return true;
    });
    steps->push_back(save("health", "health_node_lost.png"));
    steps->push_back([] {
      QApplication::exit(0);
      return true;
    });
    auto* timer = new QTimer(&window);
    auto index = std::make_shared<size_t>(0);
    QObject::connect(timer, &QTimer::timeout, &window, [steps, index] {
      if (*index < steps->size() && (*steps)[*index]()) ++*index;
    });
    timer->start(150);
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
      // A pipeline started with the studio (--pipeline, --listen): once it has shown frames.
      const bool pipeline_ready =
          !window.pipeline()->running() || window.pipeline()->lastReport().frames >= 10;
      const bool ready = pipeline_ready &&
                         (source == "none" || (grid->cameraCount() > 0 &&
                                               grid->camerasWithPictures() == grid->cameraCount() &&
                                               clock.elapsed() > 5000));
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
