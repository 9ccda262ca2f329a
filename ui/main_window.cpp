#include "ui/main_window.h"

#include <QAction>
#include <QCloseEvent>
#include <QDockWidget>
#include <QFileDialog>
#include <QFileInfo>
#include <QLabel>
#include <QMenuBar>
#include <QMessageBox>
#include <QSettings>
#include <QStatusBar>
#include <exception>

#include "core/geometry/rig_file.h"
#include "ui/rig_panel.h"
#include "ui/stage_plan_view.h"

namespace lumistage {

MainWindow::MainWindow(QWidget* parent)
    : QMainWindow(parent),
      stage_plan_(new StagePlanView(this)),
      rig_panel_(new RigPanel(this)),
      rig_dock_(new QDockWidget(tr("Cameras"), this)),
      status_(new QLabel(this)) {
  setWindowTitle(tr("Lumistage Studio"));
  setCentralWidget(stage_plan_);

  rig_dock_->setObjectName("cameras_dock");
  rig_dock_->setWidget(rig_panel_);
  addDockWidget(Qt::BottomDockWidgetArea, rig_dock_);
  connect(rig_panel_, &RigPanel::cameraSelected, stage_plan_, &StagePlanView::setHighlightedCamera);

  QMenu* file = menuBar()->addMenu(tr("&File"));
  QAction* open = file->addAction(tr("&Open rig..."), this, &MainWindow::chooseRig);
  open->setShortcut(QKeySequence::Open);
  file->addSeparator();
  QAction* quit = file->addAction(tr("&Quit"), this, &QWidget::close);
  quit->setShortcut(QKeySequence::Quit);
  QMenu* view = menuBar()->addMenu(tr("&View"));
  view->addAction(rig_dock_->toggleViewAction());

  statusBar()->addWidget(status_, 1);
  status_->setText(tr("No rig loaded"));

  QSettings settings("Lumistage", "Studio");
  restoreGeometry(settings.value("window/geometry").toByteArray());
  restoreState(settings.value("window/state").toByteArray());
  if (!settings.contains("window/geometry")) resize(1100, 820);
}

MainWindow::~MainWindow() = default;

QString MainWindow::openRig(const QString& path) {
  try {
    auto rig = std::make_unique<Rig>(loadRig(path.toStdString()));
    // Views hold a pointer to the rig: give them the new one before the old one goes.
    stage_plan_->setRig(rig.get());
    rig_panel_->setRig(rig.get());
    rig_ = std::move(rig);
    rig_path_ = path;
  } catch (const std::exception& e) {
    return QString::fromStdString(e.what());
  }
  status_->setText(tr("Rig %1: %2 cameras on %3 nodes")
                       .arg(QFileInfo(rig_path_).fileName())
                       .arg(rig_->cameraCount())
                       .arg(rig_->nodeCount()));
  setWindowTitle(tr("Lumistage Studio - %1").arg(QFileInfo(rig_path_).fileName()));
  return {};
}

void MainWindow::chooseRig() {
  const QString path =
      QFileDialog::getOpenFileName(this, tr("Open rig file"), QFileInfo(rig_path_).absolutePath(),
                                   tr("Rig files (*.yaml *.yml)"));
  if (path.isEmpty()) return;
  if (const QString error = openRig(path); !error.isEmpty()) {
    QMessageBox::warning(this, tr("Cannot open rig"), error);
  }
}

void MainWindow::closeEvent(QCloseEvent* event) {
  QSettings settings("Lumistage", "Studio");
  settings.setValue("window/geometry", saveGeometry());
  settings.setValue("window/state", saveState());
  event->accept();
}

}  // namespace lumistage
