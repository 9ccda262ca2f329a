#pragma once

#include <QString>

namespace lumistage {

class MainWindow;

// The demo's tour of the studio (lumistage-studio --demo --screenshots DIR): once the pipeline
// shows frames, the main window and each panel saved to `dir` (main_window.png, viewport.png,
// health.png, overlay.png, pipeline.png while the nodes record a take, calibration.png,
// clones.png, viewport_behind.png while the view from behind is recorded to
// viewport_behind.avi), then a node killed and health_node_lost.png saved once its cameras show
// lost; the application then quits (1 when the pipeline showed no frames in 4 minutes).
void startDemoScreenshots(MainWindow& window, const QString& dir);

// lumistage-studio --screenshot PNG: the main window saved to `png` once every camera of `source`
// has shown pictures for a few seconds (and a pipeline started with the studio has shown frames),
// or after a minute; the application then quits (1 when not every camera had a picture).
void startScreenshotWhenReady(MainWindow& window, const QString& png, const QString& source);

}  // namespace lumistage
