#pragma once

#include <QMainWindow>
#include <QString>
#include <memory>

#include "core/geometry/rig.h"

class QDockWidget;
class QLabel;
class QTabWidget;
class QThread;

namespace lumistage {

class CameraGridPanel;
class PipelinePanel;
class RigPanel;
class SourceWorker;
class StagePlanView;
struct SourceSpec;

// The studio's main window: the live cameras and the stage plan in the centre, dockable panels
// around them, the layout remembered between runs (QSettings "Lumistage/Studio").
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

  RigPanel* rigPanel() const { return rig_panel_; }
  StagePlanView* stagePlan() const { return stage_plan_; }
  CameraGridPanel* cameraGrid() const { return camera_grid_; }
  PipelinePanel* pipeline() const { return pipeline_panel_; }
  void showPipeline();  // brings the pipeline panel to the front

 signals:
  void sourceFailed(QString error);

 protected:
  void closeEvent(QCloseEvent* event) override;

 private:
  void chooseRig();
  void showRig(std::unique_ptr<Rig> rig, const QString& origin);

  std::unique_ptr<Rig> rig_;
  QString rig_path_;
  QTabWidget* tabs_;
  CameraGridPanel* camera_grid_;
  StagePlanView* stage_plan_;
  QThread* source_thread_ = nullptr;
  SourceWorker* source_worker_ = nullptr;
  RigPanel* rig_panel_;
  QDockWidget* rig_dock_;
  PipelinePanel* pipeline_panel_;
  QDockWidget* pipeline_dock_;
  QLabel* status_;
};

}  // namespace lumistage
