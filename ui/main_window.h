#pragma once

#include <QMainWindow>
#include <QString>
#include <memory>

#include "core/geometry/rig.h"
#include "core/render/clone_set.h"

class QDockWidget;
class QLabel;
class QTabWidget;
class QThread;

namespace lumistage {

class CalibrationPanel;
class CameraGridPanel;
class ClonePanel;
class DemoSession;
class HealthPanel;
class OverlayPanel;
class PipelinePanel;
class RigPanel;
class SourceWorker;
class StagePlanView;
class ViewportPanel;
struct SourceSpec;

// The studio's main window: the free-viewpoint viewport, the live cameras and the stage plan in
// the centre; dockable panels around them (camera health, skeleton overlay, calibration check,
// clones, pipeline, camera list), the layout remembered between runs (QSettings
// "Lumistage/Studio").
class MainWindow : public QMainWindow {
  Q_OBJECT

 public:
  explicit MainWindow(QWidget* parent = nullptr);
  ~MainWindow() override;

  // Loads a rig file and shows it. On failure returns the error in words (file, line, key) and
  // keeps the rig that was shown before.
  QString openRig(const QString& path);
  const Rig* rig() const { return rig_.get(); }

  // Starts streaming from a source on a worker thread (stopping any running one); the source's
  // rig replaces the loaded one. Errors arrive in sourceFailed and in the status bar.
  void startSource(const SourceSpec& spec);
  void stopSource();
  bool sourceRunning() const { return source_thread_ != nullptr; }
  // The demo: the virtual studio's demo session (made first if needed, with progress) replayed
  // as the cameras' source and run through the distributed pipeline.
  void startDemo();

  RigPanel* rigPanel() const { return rig_panel_; }
  StagePlanView* stagePlan() const { return stage_plan_; }
  CameraGridPanel* cameraGrid() const { return camera_grid_; }
  PipelinePanel* pipeline() const { return pipeline_panel_; }
  ViewportPanel* viewport() const { return viewport_panel_; }
  HealthPanel* health() const { return health_panel_; }
  OverlayPanel* overlay() const { return overlay_panel_; }
  CalibrationPanel* calibration() const { return calibration_panel_; }
  ClonePanel* clonePanel() const { return clone_panel_; }
  CloneSet& clones() { return clones_; }
  void showPipeline();  // brings the pipeline panel to the front
  // Shows a panel by name ("viewport", "cameras", "stage", "health", "overlay", "calibration",
  // "clones", "pipeline", "rig") and returns its widget (nullptr for an unknown name).
  QWidget* showPanel(const QString& name);
  void resetLayout();
  // The docks' default sizes for a window of `window`.
  void sizeDocks(const QSize& window);
  // What is being recorded, in words ("the take take-003 and the view to /data/view.avi"); empty
  // when nothing is. Closing the window while something is asks first.
  QString recordingsUnderWay() const;
  // Closes without that question: a signal (SIGTERM, Ctrl-C in the terminal) asked the studio to
  // stop, and nobody may be there to answer.
  void closeWithoutAsking();
  // Makes a whole video of a recording of the view that never closed (NAME.partial.avi, left when
  // the studio was killed, crashed or lost power while recording) on a thread of its own:
  // NAME-recovered.avi beside it (recoveredVideoPath), `partial` kept as it is. The status bar and
  // recordingRecovered() say how it went. The studio offers it by itself: at start-up for the
  // recording it had open when it last ended without closing it, and when a recording finds a
  // partial file of its name left by an earlier one (File > Recover a recording of the view...
  // for any other).
  void recoverRecording(const QString& partial);

 signals:
  void sourceFailed(QString error);
  void demoFailed(QString error);
  // recoverRecording() ended: the video made, or (video empty) why none was.
  void recordingRecovered(QString video, QString error);

 protected:
  void closeEvent(QCloseEvent* event) override;

 private:
  void chooseRig();
  void showRig(std::unique_ptr<Rig> rig, const QString& origin);
  QDockWidget* addDock(const QString& title, const QString& name, QWidget* panel,
                       Qt::DockWidgetArea area);
  void startDemoOn(const QString& session);
  // Asks whether to recover `partial` (recoverRecording), without waiting for the answer.
  // `studio_ended`: the studio ended while recording it; otherwise a new recording found it.
  void offerRecovery(const QString& partial, bool studio_ended);
  void chooseRecording();

  std::unique_ptr<Rig> rig_;
  QString rig_path_;
  CloneSet clones_;
  QTabWidget* tabs_;
  ViewportPanel* viewport_panel_;
  CameraGridPanel* camera_grid_;
  StagePlanView* stage_plan_;
  QThread* source_thread_ = nullptr;
  SourceWorker* source_worker_ = nullptr;
  int source_generation_ = 0;  // sources started, so that a late 'finished' stops no later one
  RigPanel* rig_panel_;
  PipelinePanel* pipeline_panel_;
  HealthPanel* health_panel_;
  OverlayPanel* overlay_panel_;
  CalibrationPanel* calibration_panel_;
  ClonePanel* clone_panel_;
  DemoSession* demo_session_;
  QDockWidget *rig_dock_, *pipeline_dock_, *health_dock_, *overlay_dock_, *calibration_dock_,
      *clone_dock_;
  QByteArray default_state_;
  QLabel* status_;
  QString report_error_;  // why the rig's calibration report was not used (empty: it was, or none)
  bool close_without_asking_ = false;
  QList<QThread*> recoveries_;  // recoverRecording()'s, until they end
};

}  // namespace lumistage
