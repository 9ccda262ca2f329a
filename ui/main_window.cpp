#include "ui/main_window.h"

#include <QAbstractButton>
#include <QAction>
#include <QCloseEvent>
#include <QComboBox>
#include <QCoreApplication>
#include <QDockWidget>
#include <QFileDialog>
#include <QFileInfo>
#include <QLabel>
#include <QMenuBar>
#include <QMessageBox>
#include <QScreen>
#include <QSettings>
#include <QStatusBar>
#include <QTabWidget>
#include <QThread>
#include <QTimer>
#include <algorithm>
#include <exception>
#include <filesystem>

#include "core/calib/calibration_report.h"
#include "core/geometry/rig_file.h"
#include "core/geometry/stage_volume.h"
#include "core/render/view_recorder.h"
#include "ui/calibration_panel.h"
#include "ui/camera_grid_panel.h"
#include "ui/clone_panel.h"
#include "ui/demo_session.h"
#include "ui/health_panel.h"
#include "ui/overlay_panel.h"
#include "ui/pipeline_panel.h"
#include "ui/rig_panel.h"
#include "ui/source_worker.h"
#include "ui/stage_plan_view.h"
#include "ui/viewport_panel.h"

namespace lumistage {

namespace {
constexpr int kLayoutVersion = 2;  // of saveState: panels added since version 1
// The view's recording under way (its partial file) and the studio process recording it, kept in
// the settings until the recording ends: found at start-up, the studio ended without closing it.
constexpr char kOpenRecording[] = "recording/open";
constexpr char kOpenRecordingPid[] = "recording/open_pid";
}  // namespace

MainWindow::MainWindow(QWidget* parent)
    : QMainWindow(parent),
      tabs_(new QTabWidget(this)),
      viewport_panel_(new ViewportPanel(&clones_, this)),
      camera_grid_(new CameraGridPanel(this)),
      stage_plan_(new StagePlanView(this)),
      rig_panel_(new RigPanel(this)),
      pipeline_panel_(new PipelinePanel(this)),
      health_panel_(new HealthPanel(this)),
      overlay_panel_(new OverlayPanel(this)),
      calibration_panel_(new CalibrationPanel(this)),
      clone_panel_(new ClonePanel(&clones_, this)),
      demo_session_(new DemoSession(this)),
      status_(new QLabel(this)) {
  status_->setObjectName("status");
  setWindowTitle(tr("Lumistage Studio"));
  setDockNestingEnabled(true);
  qRegisterMetaType<std::shared_ptr<const lumistage::Rig>>();
  qRegisterMetaType<QVector<lumistage::CameraStatus>>();
  tabs_->addTab(viewport_panel_, tr("Viewport"));
  tabs_->addTab(camera_grid_, tr("Cameras"));
  tabs_->addTab(stage_plan_, tr("Stage"));
  setCentralWidget(tabs_);

  // Right: camera health above the skeleton overlay (and the clones); bottom: the pipeline, the
  // calibration check and the camera list.
  health_dock_ =
      addDock(tr("Camera health"), "health_dock", health_panel_, Qt::RightDockWidgetArea);
  overlay_dock_ =
      addDock(tr("Skeleton overlay"), "overlay_dock", overlay_panel_, Qt::RightDockWidgetArea);
  clone_dock_ = addDock(tr("Clones"), "clones_dock", clone_panel_, Qt::RightDockWidgetArea);
  pipeline_dock_ =
      addDock(tr("Pipeline"), "pipeline_dock", pipeline_panel_, Qt::BottomDockWidgetArea);
  calibration_dock_ = addDock(tr("Calibration check"), "calibration_dock", calibration_panel_,
                              Qt::BottomDockWidgetArea);
  rig_dock_ = addDock(tr("Cameras"), "cameras_dock", rig_panel_, Qt::BottomDockWidgetArea);
  // On a laptop's screen (under 900 lines) the camera health has the right column to itself, the
  // overlay and the clones tabs beside it: split with them, its table kept under two rows.
  const bool short_screen = screen()->availableGeometry().height() < 900;
  if (short_screen)
    tabifyDockWidget(health_dock_, overlay_dock_);
  else
    splitDockWidget(health_dock_, overlay_dock_, Qt::Vertical);
  tabifyDockWidget(overlay_dock_, clone_dock_);
  tabifyDockWidget(pipeline_dock_, calibration_dock_);
  tabifyDockWidget(pipeline_dock_, rig_dock_);
  pipeline_dock_->raise();
  (short_screen ? health_dock_ : overlay_dock_)->raise();
  sizeDocks(QSize(1600, 1000));

  connect(rig_panel_, &RigPanel::cameraSelected, stage_plan_, &StagePlanView::setHighlightedCamera);
  connect(viewport_panel_, &ViewportPanel::viewChanged, pipeline_panel_, &PipelinePanel::setView);
  connect(pipeline_panel_, &PipelinePanel::snapshot, viewport_panel_->viewport(),
          &ViewportWidget::showSnapshot);
  connect(pipeline_panel_, &PipelinePanel::view, viewport_panel_->viewport(),
          &ViewportWidget::showView);
  connect(pipeline_panel_, &PipelinePanel::snapshot, health_panel_, &HealthPanel::showSnapshot);
  connect(pipeline_panel_, &PipelinePanel::snapshot, overlay_panel_, &OverlayPanel::showSnapshot);
  connect(overlay_panel_, &OverlayPanel::cameraSelected, this, [this](int camera) {
    if (source_worker_) source_worker_->watchCamera(camera);
  });
  connect(pipeline_panel_, &PipelinePanel::demoSessionWanted, this, &MainWindow::startDemo);
  connect(viewport_panel_, &ViewportPanel::recordingRequested, this, [this](const QString& file) {
    if (pipeline_panel_->startRecording(file)) return;
    viewport_panel_->record(false);
    status_->setText(tr("Nothing to record: start the pipeline first"));
  });
  connect(viewport_panel_, &ViewportPanel::recordingStopped, pipeline_panel_,
          &PipelinePanel::stopRecording);
  connect(pipeline_panel_, &PipelinePanel::recordingEnded, viewport_panel_,
          &ViewportPanel::recordingEnded);
  connect(pipeline_panel_, &PipelinePanel::recordingStarted, this,
          [this](const QString& partial, const QString& leftover) {
            QSettings settings("Lumistage", "Studio");
            settings.setValue(kOpenRecording, partial);
            settings.setValue(kOpenRecordingPid, QCoreApplication::applicationPid());
            if (!leftover.isEmpty() && !wasRecovered(leftover.toStdString()))
              offerRecovery(leftover, false);
          });
  connect(pipeline_panel_, &PipelinePanel::recordingEnded, this, [] {
    QSettings settings("Lumistage", "Studio");
    settings.remove(kOpenRecording);
    settings.remove(kOpenRecordingPid);
  });
  connect(viewport_panel_->viewport(), &ViewportWidget::clonesChanged, clone_panel_,
          &ClonePanel::refresh);
  connect(clone_panel_, &ClonePanel::clonesChanged, this, [this] {
    viewport_panel_->viewport()->refresh();
    pipeline_panel_->setView(viewport_panel_->viewport()->viewData());  // the nodes draw them
  });
  connect(demo_session_, &DemoSession::made, this, &MainWindow::startDemoOn);
  connect(demo_session_, &DemoSession::failed, this, [this](const QString& error) {
    status_->setText(tr("No demo session: %1").arg(error));
    if (error != tr("cancelled")) {
      QMessageBox::warning(this, tr("Cannot make the demo session"), error);
    }
    emit demoFailed(error);
  });

  QMenu* file = menuBar()->addMenu(tr("&File"));
  QAction* open = file->addAction(tr("&Open rig..."), this, &MainWindow::chooseRig);
  open->setShortcut(QKeySequence::Open);
  file->addAction(tr("Run the &demo (virtual studio)"), this, &MainWindow::startDemo);
  file->addAction(tr("&Recover a recording of the view..."), this, &MainWindow::chooseRecording);
  file->addSeparator();
  QAction* quit = file->addAction(tr("&Quit"), this, &QWidget::close);
  quit->setShortcut(QKeySequence::Quit);
  QMenu* view = menuBar()->addMenu(tr("&View"));
  for (QDockWidget* dock :
       {health_dock_, overlay_dock_, calibration_dock_, clone_dock_, pipeline_dock_, rig_dock_})
    view->addAction(dock->toggleViewAction());
  view->addSeparator();
  view->addAction(tr("&Reset layout"), this, &MainWindow::resetLayout);

  statusBar()->addWidget(status_, 1);
  status_->setText(tr("No rig loaded"));

  default_state_ = saveState(kLayoutVersion);
  QSettings settings("Lumistage", "Studio");
  restoreGeometry(settings.value("window/geometry").toByteArray());
  restoreState(settings.value("window/state").toByteArray(), kLayoutVersion);
  if (!settings.contains("window/geometry")) {
    // 1600x1000, or the screen less room for the window's frame on a smaller one (a laptop's).
    const QSize room = screen()->availableGeometry().size() - QSize(16, 48);
    resize(QSize(1600, 1000).boundedTo(room).expandedTo(minimumSizeHint()));
    sizeDocks(size());
  }
  QComboBox* size = viewport_panel_->sizeChoice();
  const int chosen = size->findData(
      settings.value("viewport/render_width", viewport_panel_->viewport()->renderWidth()).toInt());
  if (chosen >= 0) size->setCurrentIndex(chosen);

  // A recording of the view that the last studio left open (killed, crashed, power lost): offered
  // for recovery once the window is up. Not while the studio that records it still runs.
  const QString left_open = settings.value(kOpenRecording).toString();
  const qint64 pid = settings.value(kOpenRecordingPid).toLongLong();
  const bool recording_elsewhere = pid != QCoreApplication::applicationPid() && pid > 0 &&
                                   QFileInfo::exists(QString("/proc/%1").arg(pid));
  if (!left_open.isEmpty() && !recording_elsewhere) {
    settings.remove(kOpenRecording);
    settings.remove(kOpenRecordingPid);
    if (pid != QCoreApplication::applicationPid() && QFileInfo::exists(left_open))
      QTimer::singleShot(0, this, [this, left_open] { offerRecovery(left_open, true); });
  }
}

MainWindow::~MainWindow() {
  stopSource();
  for (QThread* recovery : recoveries_) {  // a video half made would be left out of its place
    recovery->wait();
    delete recovery;
  }
}

QDockWidget* MainWindow::addDock(const QString& title, const QString& name, QWidget* panel,
                                 Qt::DockWidgetArea area) {
  auto* dock = new QDockWidget(title, this);
  dock->setObjectName(name);
  dock->setWidget(panel);
  addDockWidget(area, dock);
  return dock;
}

void MainWindow::sizeDocks(const QSize& window) {
  resizeDocks({health_dock_}, {620}, Qt::Horizontal);
  resizeDocks({health_dock_, overlay_dock_}, {520, 380}, Qt::Vertical);  // when split
  resizeDocks({pipeline_dock_}, {std::min(270, window.height() / 4)}, Qt::Vertical);
}

void MainWindow::resetLayout() {
  restoreState(default_state_, kLayoutVersion);
  sizeDocks(size());
  for (QDockWidget* dock :
       {health_dock_, overlay_dock_, calibration_dock_, clone_dock_, pipeline_dock_, rig_dock_})
    dock->show();
}

QWidget* MainWindow::showPanel(const QString& name) {
  const struct {
    const char* name;
    QDockWidget* dock;
  } docks[] = {{"health", health_dock_},           {"overlay", overlay_dock_},
               {"calibration", calibration_dock_}, {"clones", clone_dock_},
               {"pipeline", pipeline_dock_},       {"rig", rig_dock_}};
  for (const auto& d : docks) {
    if (name == d.name) {
      d.dock->show();
      d.dock->raise();
      return d.dock->widget();
    }
  }
  const struct {
    const char* name;
    QWidget* tab;
  } tabs[] = {{"viewport", viewport_panel_}, {"cameras", camera_grid_}, {"stage", stage_plan_}};
  for (const auto& t : tabs) {
    if (name == t.name) {
      tabs_->setCurrentWidget(t.tab);
      return t.tab;
    }
  }
  return nullptr;
}

void MainWindow::showRig(std::unique_ptr<Rig> rig, const QString& origin) {
  // Views hold a pointer to the rig: give them the new one before the old one goes.
  const StageBox stage = stageVolume(*rig);  // searched once, drawn by both views
  stage_plan_->setRig(rig.get(), stage);
  rig_panel_->setRig(rig.get());
  camera_grid_->setRig(*rig);
  viewport_panel_->setRig(*rig, stage);
  health_panel_->setRig(*rig);
  overlay_panel_->setRig(*rig);
  calibration_panel_->setRig(*rig);
  rig_ = std::move(rig);
  status_->setText(
      tr("%1: %2 cameras on %3 nodes").arg(origin).arg(rig_->cameraCount()).arg(rig_->nodeCount()) +
      (report_error_.isEmpty() ? QString() : " · " + report_error_));
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
  // A calibration report beside the rig gives the calibration check its reprojection errors:
  // the one `lumistage calibrate` wrote with the rig, or one in the JSON form other tools write.
  const QFileInfo rig_file(path);
  QString report = QString::fromStdString(
      calibrationReportPathFor(rig_file.absoluteFilePath().toStdString()).string());
  if (!QFileInfo::exists(report)) report = rig_file.absolutePath() + "/calibration_report.json";
  ReprojectionErrors errors;
  // Said with the rig (showRig) for as long as it is shown (the source's messages would
  // overwrite it).
  report_error_.clear();
  if (QFileInfo::exists(report)) {
    if (const QString error = loadCalibrationReport(report, errors); !error.isEmpty())
      report_error_ = tr("Calibration report ignored: %1").arg(error);
  }
  showRig(std::move(rig), tr("Rig %1").arg(rig_file.fileName()));
  calibration_panel_->setReprojectionErrors(errors);
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
  // A source that fails is cleaned up as by stopSource(), which deletes the worker once its
  // thread has ended, so source_worker_ never points at a deleted one.
  connect(
      worker, &SourceWorker::finished, this,
      [this, generation = ++source_generation_] {
        if (generation == source_generation_) stopSource();
      },
      Qt::QueuedConnection);
  connect(worker, &SourceWorker::opened, this,
          [this](std::shared_ptr<const Rig> rig, const QString& description) {
            showRig(std::make_unique<Rig>(*rig), description);
          });
  connect(worker, &SourceWorker::failed, this, [this](const QString& error) {
    status_->setText(tr("Source stopped: %1").arg(error));
    emit sourceFailed(error);
  });
  connect(worker, &SourceWorker::frame, camera_grid_, &CameraGridPanel::showFrame);
  connect(worker, &SourceWorker::frame, health_panel_, &HealthPanel::showFrame);
  connect(worker, &SourceWorker::frame, overlay_panel_, &OverlayPanel::showFrame);
  connect(worker, &SourceWorker::watchedFrame, overlay_panel_, &OverlayPanel::showWatchedFrame);
  worker->watchCamera(overlay_panel_->selectedCamera());
  connect(worker, &SourceWorker::frame, calibration_panel_, &CalibrationPanel::showFrame);
  connect(worker, &SourceWorker::status, camera_grid_, &CameraGridPanel::showStatus);
  connect(worker, &SourceWorker::status, health_panel_, &HealthPanel::showStatus);
  status_->setText(tr("Opening %1...").arg(spec.describe()));
  source_thread_->start();
}

void MainWindow::startDemo() {
  if (DemoSession::exists()) {
    startDemoOn(DemoSession::folder());
    return;
  }
  status_->setText(tr("Filming the virtual studio for the demo (once)..."));
  demo_session_->make(this);
}

void MainWindow::startDemoOn(const QString& session) {
  pipeline_panel_->setDemoSession(session);
  SourceSpec spec;
  if (const QString error = SourceSpec::parse("session:" + session, spec); !error.isEmpty()) {
    emit demoFailed(error);
    return;
  }
  spec.from_memory = true;  // decoding 12 cameras' PNGs at 30 Hz would take a core
  startSource(spec);
  LocalRunOptions options;
  options.session = session.toStdString();
  options.replay = "memory";  // decoded up front, then looped at its frame rate
  pipeline_panel_->setView(viewport_panel_->viewport()->viewData());
  pipeline_panel_->start(options);
}

void MainWindow::showPipeline() {
  pipeline_dock_->show();
  pipeline_dock_->raise();
}

void MainWindow::stopSource() {
  if (!source_thread_) return;
  source_worker_->stop();
  source_thread_->quit();
  source_thread_->wait();
  delete source_worker_;  // its thread has ended
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

void MainWindow::chooseRecording() {
  const QString partial = QFileDialog::getOpenFileName(
      this, tr("Recover a recording of the view"), QString(),
      tr("Recordings that never closed (*.partial.avi *.partial-*.avi *.partial.mp4 "
         "*.partial-*.mp4);;Videos (*.avi *.mp4)"));
  if (!partial.isEmpty()) recoverRecording(partial);
}

void MainWindow::offerRecovery(const QString& partial, bool studio_ended) {
  const QString video = QString::fromStdString(recoveredVideoPath(partial.toStdString()).string());
  auto* box = new QMessageBox(
      QMessageBox::Question, tr("Recover a recording"),
      studio_ended ? tr("The studio ended while it was recording the view, without closing the "
                        "video.")
                   : tr("A recording of the view under this name never closed. The recording "
                        "just started goes beside it."),
      QMessageBox::Yes | QMessageBox::No, this);
  box->setInformativeText(
      tr("Recover its whole frames into\n%1?\n\nThe video left open, kept as it is:\n%2")
          .arg(video, partial));
  box->button(QMessageBox::Yes)->setText(tr("Recover"));
  box->button(QMessageBox::No)->setText(tr("Not now"));
  box->setDefaultButton(QMessageBox::Yes);
  box->setAttribute(Qt::WA_DeleteOnClose);
  connect(box, &QMessageBox::buttonClicked, this, [this, box, partial](QAbstractButton* button) {
    if (box->standardButton(button) == QMessageBox::Yes) recoverRecording(partial);
  });
  box->open();
}

void MainWindow::recoverRecording(const QString& partial) {
  const std::filesystem::path in = partial.toStdString();
  const std::filesystem::path out = recoveredVideoPath(in);
  const QString video = QString::fromStdString(out.string());
  struct Outcome {
    RecoveredVideo video;
    QString error;
  };
  auto outcome = std::make_shared<Outcome>();
  QThread* thread = QThread::create([in, out, outcome] {
    try {
      outcome->video = recoverPartialVideo(in, out);
    } catch (const std::exception& e) {
      outcome->error = QString::fromStdString(e.what());
    }
  });
  recoveries_.append(thread);
  connect(thread, &QThread::finished, this, [this, thread, outcome, video] {
    recoveries_.removeOne(thread);
    thread->deleteLater();
    if (!outcome->error.isEmpty()) {
      status_->setText(tr("Cannot recover the recording: %1").arg(outcome->error));
      emit recordingRecovered(QString(), outcome->error);
      return;
    }
    const RecoveredVideo& r = outcome->video;
    status_->setText(
        tr("Recovered %1 frames (%2 s) of the view into %3%4")
            .arg(r.frames)
            .arg(r.fps > 0 ? r.frames / r.fps : 0.0, 0, 'f', 1)
            .arg(video)
            .arg(r.bytes_cut > 0 ? tr("; the last frame, cut short, left out") : QString()));
    emit recordingRecovered(video, QString());
  });
  status_->setText(tr("Recovering %1 into %2...").arg(partial, video));
  thread->start();
}

QString MainWindow::recordingsUnderWay() const {
  QStringList what;
  const PipelineSnapshot& s = pipeline_panel_->lastSnapshot();
  if (pipeline_panel_->running() && s.take_recording)
    what << tr("the take %1").arg(QString::fromStdString(s.take.take));
  if (viewport_panel_->recording())
    what << (s.recording.isEmpty() ? tr("the view") : tr("the view to %1").arg(s.recording));
  return what.join(tr(" and "));
}

void MainWindow::closeWithoutAsking() {
  close_without_asking_ = true;
  close();
}

void MainWindow::closeEvent(QCloseEvent* event) {
  // A stray click on the window's close button must not end a take: ask first.
  if (const QString what = recordingsUnderWay(); !what.isEmpty() && !close_without_asking_) {
    const QMessageBox::StandardButton answer = QMessageBox::question(
        this, tr("Recording"),
        tr("Recording %1.\n\nClosing the studio stops recording; what was recorded so far "
           "is kept. Close the studio?")
            .arg(what),
        QMessageBox::Close | QMessageBox::Cancel, QMessageBox::Cancel);
    if (answer != QMessageBox::Close) {
      event->ignore();
      return;
    }
  }
  stopSource();
  pipeline_panel_->stop();
  demo_session_->cancel();
  QSettings settings("Lumistage", "Studio");
  settings.setValue("window/geometry", saveGeometry());
  settings.setValue("window/state", saveState(kLayoutVersion));
  settings.setValue("viewport/render_width", viewport_panel_->viewport()->renderWidth());
  event->accept();
}

}  // namespace lumistage
