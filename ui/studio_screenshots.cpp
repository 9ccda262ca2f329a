// The studio's screenshots: the demo's tour of every panel, and one of the main window.
#include "ui/studio_screenshots.h"

#include <QApplication>
#include <QDir>
#include <QElapsedTimer>
#include <QTimer>
#include <cstdio>
#include <functional>
#include <memory>
#include <vector>

#include "ui/calibration_panel.h"
#include "ui/camera_grid_panel.h"
#include "ui/clone_panel.h"
#include "ui/health_panel.h"
#include "ui/main_window.h"
#include "ui/overlay_panel.h"
#include "ui/pipeline_panel.h"
#include "ui/viewport_panel.h"

namespace lumistage {

namespace {

using Steps = std::vector<std::function<bool()>>;

// A step that saves `panel` (the main window when empty) to dir/file.
std::function<bool()> saveStep(MainWindow& window, const QString& dir, const QString& panel,
                               const QString& file) {
  return [&window, dir, panel, file] {
    QWidget* widget = panel.isEmpty() ? &window : window.showPanel(panel);
    const bool ok = widget && widget->grab().save(dir + "/" + file);
    std::fprintf(ok ? stdout : stderr, "%s %s/%s\n", ok ? "saved" : "cannot save", qPrintable(dir),
                 qPrintable(file));
    return true;
  };
}

// The view from behind the actor, recorded meanwhile to viewport_behind.avi, saved once the nodes
// have rendered it.
void addViewBehindSteps(MainWindow& window, const QString& dir, Steps& steps) {
  auto* pipeline = window.pipeline();
  steps.push_back([&window, dir] {
    OrbitView view = OrbitView::studioDefault();
    view.orbit(3.14159265, 0);
    window.viewport()->viewport()->setView(view);
    // Recording the director's view meanwhile: the viewport shows it (REC, frames so far).
    window.viewport()->record(true, dir + "/viewport_behind.avi");
    return true;
  });
  // The nodes render the new view: wait for a frame of it.
  auto turned_at = std::make_shared<int64_t>(-1);
  steps.push_back([pipeline, turned_at] {
    if (*turned_at < 0) *turned_at = pipeline->lastReport().frames;
    return pipeline->lastReport().frames > *turned_at + 10;
  });
  steps.push_back(saveStep(window, dir, "viewport", "viewport_behind.png"));
  steps.push_back([&window] {
    window.viewport()->record(false);
    return true;
  });
}

void addNodeLossSteps(MainWindow& window, const QString& dir, Steps& steps) {
  // A technician's check: kill a node and time how long its cameras take to show "lost".
  auto killed = std::make_shared<QElapsedTimer>();
  auto shown_after_ms = std::make_shared<qint64>(-1);
  steps.push_back([&window, killed, shown_after_ms] {
    window.showPanel("health");
    // When the health panel (connected before this) first says "lost" for node2's cameras.
    QObject::connect(window.pipeline(), &PipelinePanel::snapshot, &window,
                     [killed, shown_after_ms](const PipelineSnapshot& s) {
                       if (*shown_after_ms < 0 && killed->isValid() && s.exited.contains("node2"))
                         *shown_after_ms = killed->elapsed();
                     });
    window.pipeline()->killNode("node2");
    killed->start();
    return true;
  });
  steps.push_back([&window, killed, shown_after_ms] {
    auto* health = window.health();
    const Rig* rig = window.rig();
    int camera = -1;
    for (int c = 0; rig && c < rig->cameraCount(); ++c) {
      if (rig->camera(c).node() == "node2") camera = c;
    }
    if (camera < 0) return true;
    if (health->verdict(camera).state != HealthState::kLost) return false;
    std::printf(
        "node2 killed: the health panel had it lost after %lld ms (seen by this check after "
        "%lld ms)\n",
        static_cast<long long>(*shown_after_ms), static_cast<long long>(killed->elapsed()));
    return true;
  });
  steps.push_back(saveStep(window, dir, "health", "health_node_lost.png"));
}

}  // namespace

void startDemoScreenshots(MainWindow& window, const QString& dir) {
  QDir().mkpath(dir);
  window.resize(1600, 1000);
  window.resetLayout();  // the default layout, whatever was remembered
  // Steps a few hundred milliseconds apart, so that each panel is painted before it is grabbed.
  auto steps = std::make_shared<Steps>();
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
  steps->push_back(saveStep(window, dir, "", "main_window.png"));
  steps->push_back(saveStep(window, dir, "viewport", "viewport.png"));
  steps->push_back(saveStep(window, dir, "health", "health.png"));
  steps->push_back([&window] {
    window.overlay()->selectCamera(2);  // cam03 sees the actor's side: the arms spread
    return true;
  });
  steps->push_back(saveStep(window, dir, "overlay", "overlay.png"));
  // A take: every node records its cameras; the panel shows it recording.
  steps->push_back([pipeline] { return pipeline->startTake("take-001"); });
  steps->push_back([pipeline] {
    int recording = 0;
    for (const NodeReport& n : pipeline->lastReport().nodes)
      recording += n.take.take == "take-001" && n.take.written >= 10;
    return recording == static_cast<int>(pipeline->lastReport().nodes.size());
  });
  steps->push_back(saveStep(window, dir, "pipeline", "pipeline.png"));
  steps->push_back([pipeline] {
    pipeline->stopTake();
    return true;
  });
  steps->push_back([&window] {
    // A point on the chest (spine3) in the first camera: its epipolar lines in the others.
    auto* cal = window.calibration();
    const Rig* rig = window.rig();
    if (rig && rig->cameraCount() > 1) {
      const auto& snap = window.pipeline()->lastSnapshot();
      const Eigen::Vector3d chest =
          snap.joints.size() > 3 ? snap.joints[3] : Eigen::Vector3d(0, 0, 1.3);
      if (const auto p = rig->camera(0).project(chest)) cal->pickPoint(0, *p);
    }
    return true;
  });
  steps->push_back(saveStep(window, dir, "calibration", "calibration.png"));
  steps->push_back([&window] {
    // Two clones, the view from behind the actor (a half turn from the default).
    window.showPanel("clones");
    window.clonePanel()->addClone();
    window.clonePanel()->addClone();
    window.clonePanel()->turnSelected(3.14159265 / 2);
    window.showPanel("viewport");
    return true;
  });
  steps->push_back(saveStep(window, dir, "clones", "clones.png"));
  addViewBehindSteps(window, dir, *steps);
  addNodeLossSteps(window, dir, *steps);
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

void startScreenshotWhenReady(MainWindow& window, const QString& png, const QString& source) {
  // Once every camera has shown pictures and counters for a few seconds (or after a minute; at
  // once without a source).
  QObject::connect(&window, &MainWindow::sourceFailed, &window, [](const QString& error) {
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

}  // namespace lumistage
