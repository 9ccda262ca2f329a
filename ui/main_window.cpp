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
#include <QTabWidget>
#include <QThread>
#include <exception>

#include "core/geometry/rig_file.h"
#include "ui/camera_grid_panel.h"
#include "ui/pipeline_panel.h"
#include "ui/rig_panel.h"
#include "ui/source_worker.h"
#include "ui/stage_plan_view.h"

namespace lumistage {

MainWindow::MainWindow(QWidget* parent)
    : QMainWindow(parent),
      tabs_(new QTabWidget(this)),
      camera_grid_(new CameraGridPanel(this)),
      stage_plan_(new StagePlanView(this)),
      rig_panel_(new RigPanel(this)),
      rig_dock_(new QDockWidget(tr("Cameras"), this)),
      pipeline_panel_(new PipelinePanel(this)),
      pipeline_dock_(new QDockWidget(tr("Pipeline"), this)),
      status_(new QLabel(this)) {
  setWindowTitle(tr("Lumistage Studio"));
  qRegisterMetaType<std::shared_ptr<const lumistage::Rig>>();
  qRegisterMetaType<QVector<lumistage::CameraStatus>>();
  tabs_->addTab(camera_grid_, tr("Cameras"));
  tabs_->addTab(stage_plan_, tr("Stage"));
  setCentralWidget(tabs_);

  rig_dock_->setObjectName("cameras_dock");
  rig_dock_->setWidget(rig_panel_);
  addDockWidget(Qt::BottomDockWidgetArea, rig_dock_);
  pipeline_dock_->setObjectName("pipeline_dock");
  pipeline_dock_->setWidget(pipeline_panel_);
  addDockWidget(Qt::BottomDockWidgetArea, pipeline_dock_);
  tabifyDockWidget(rig_dock_, pipeline_dock_);
  connect(rig_panel_, &RigPanel::cameraSelected, stage_plan_, &StagePlanView::setHighlightedCamera);

  QMenu* file = menuBar()->addMenu(tr("&File"));
  QAction* open = file->addAction(tr("&Open rig..."), this, &MainWindow::chooseRig);
  open->setShortcut(QKeySequence::Open);
  file->addSeparator();
  QAction* quit = file->addAction(tr("&Quit"), this, &QWidget::close);
  quit->setShortcut(QKeySequence::Quit);
  QMenu* view = menuBar()->addMenu(tr("&View"));
  view->addAction(rig_dock_->toggleViewAction());
  view->addAction(pipeline_dock_->toggleViewAction());

  statusBar()->addWidget(status_, 1);
  status_->setText(tr("No rig loaded"));

  QSettings settings("Lumistage", "Studio");
  restoreGeometry(settings.value("window/geometry").toByteArray());
  restoreState(settings.value("window/state").toByteArray());
  if (!settings.contains("window/geometry")) resize(1100, 820);
}

MainWindow::~MainWindow() {
  stopSource();
}

void MainWindow::showRig(std::unique_ptr<Rig> rig, const QString& origin) {
  // Views hold a pointer to the rig: give them the new one before the old one goes.
  stage_plan_->setRig(rig.get());
  rig_panel_->setRig(rig.get());
  camera_grid_->setRig(*rig);
  rig_ = std::move(rig);
  status_->setText(
      tr("%1: %2 cameras on %3 nodes").arg(origin).arg(rig_->cameraCount()).arg(rig_->nodeCount()));
  setWindowTitle(tr("Lumistage Studio - %1").arg(origin));
}

QString MainWindow::openRig(const QString& path) {
  std::unique_ptr<Rig> rig;
  try {
    rig = std::make_unique<Rig>(loadRig(path.toStdString()));
  } catch (const std::exception& e) {
    return QString::fromStdString(e.what());
  }
  rig_path_ = path;
  showRig(std::move(rig), tr("Rig %1").arg(QFileInfo(path).fileName()));
  return {};
}

void MainWindow::startSource(const SourceSpec& spec) {
  stopSource();
  source_thread_ = new QThread(this);
  SourceWorker* worker = new SourceWorker(spec);
  source_worker_ = worker;
  worker->moveToThread(source_thread_);
  connect(source_thread_, &QThread::started, worker, &SourceWorker::run);
  connect(worker, &SourceWorker::finished, source_thread_, &QThread::quit);
  connect(source_thread_, &QThread::finished, worker, &QObject::deleteLater);
  connect(worker, &SourceWorker::opened, this,
          [this](std::shared_ptr<const Rig> rig, const QString& description) {
            showRig(std::make_unique<Rig>(*rig), description);
          });
  connect(worker, &SourceWorker::failed, this, [this](const QString& error) {
    status_->setText(tr("Source stopped: %1").arg(error));
    emit sourceFailed(error);
  });
  connect(worker, &SourceWorker::frame, camera_grid_, &CameraGridPanel::showFrame);
  connect(worker, &SourceWorker::status, camera_grid_, &CameraGridPanel::showStatus);
  status_->setText(tr("Opening %1...").arg(spec.describe()));
  source_thread_->start();
}

void MainWindow::showPipeline() {
  pipeline_dock_->show();
  pipeline_dock_->raise();
}

void MainWindow::stopSource() {
  if (!source_thread_) return;
  if (source_worker_) source_worker_->stop();  // the worker is alive until its thread finishes
  source_thread_->quit();
  source_thread_->wait();
  delete source_thread_;
  source_thread_ = nullptr;
  source_worker_ = nullptr;
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
  stopSource();
  pipeline_panel_->stop();
  QSettings settings("Lumistage", "Studio");
  settings.setValue("window/geometry", saveGeometry());
  settings.setValue("window/state", saveState());
  event->accept();
}

}  // namespace lumistage
