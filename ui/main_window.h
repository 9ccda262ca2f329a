#pragma once

#include <QMainWindow>
#include <QString>
#include <memory>

#include "core/geometry/rig.h"

class QDockWidget;
class QLabel;

namespace lumistage {

class RigPanel;
class StagePlanView;

// The studio's main window: the stage plan in the centre, dockable panels around it, the layout
// remembered between runs (QSettings "Lumistage/Studio").
class MainWindow : public QMainWindow {
  Q_OBJECT

 public:
  explicit MainWindow(QWidget* parent = nullptr);
  ~MainWindow() override;

  // Loads a rig file and shows it. On failure returns the error in words (file, line, key) and
  // keeps the rig that was shown before.
  QString openRig(const QString& path);
  const Rig* rig() const { return rig_.get(); }

  RigPanel* rigPanel() const { return rig_panel_; }
  StagePlanView* stagePlan() const { return stage_plan_; }

 protected:
  void closeEvent(QCloseEvent* event) override;

 private:
  void chooseRig();

  std::unique_ptr<Rig> rig_;
  QString rig_path_;
  StagePlanView* stage_plan_;
  RigPanel* rig_panel_;
  QDockWidget* rig_dock_;
  QLabel* status_;
};

}  // namespace lumistage
