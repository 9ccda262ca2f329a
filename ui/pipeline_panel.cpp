#include "ui/pipeline_panel.h"

#include <QComboBox>
#include <QDir>
#include <QFileDialog>
#include <QFileInfo>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QInputDialog>
#include <QLineEdit>
#include <QMessageBox>
#include <QPixmap>
#include <QPushButton>
#include <QSettings>
#include <QTableWidget>
#include <QThread>
#include <QVBoxLayout>
#include <algorithm>
#include <exception>
#include <map>

#include "core/base/output_path.h"
#include "core/body/human_model.h"
#include "ui/live_table.h"

namespace lumistage {

namespace {

// Recording time in words: "2 h 05 min", "12 min", "40 s".
QString durationWords(double seconds) {
  const int64_t s = int64_t(std::clamp(seconds, 0.0, 1e9));  // (a node's odd rate: no overflow)
  if (s >= 3600)
    return QObject::tr("%1 h %2 min").arg(s / 3600).arg((s % 3600) / 60, 2, 10, QChar('0'));
  if (s >= 60) return QObject::tr("%1 min").arg(s / 60);
  return QObject::tr("%1 s").arg(s);
}

// Under this much recording time left on a node's disk, its Take cell turns red.
constexpr double kLowDiskSeconds = 10 * 60;

// The source box's entries, in order.
enum SourceEntry { kDemoSession = 0, kRecordedSession, kAravisCameras, kStageNodes };

}  // namespace

PipelinePanel::PipelinePanel(QWidget* parent)
    : QWidget(parent),
      summary_(new QLabel(
          tr("Not running. Start runs the distributed pipeline: a node process per rig node, "
             "the studio's modules here."),
          this)),
      view_(new QLabel(this)),
      table_(new QTableWidget(this)),
      stages_(new QTableWidget(this)),
      source_(new QComboBox(this)),
      body_(new QComboBox(this)),
      start_button_(new QPushButton(tr("Start"), this)),
      stop_button_(new QPushButton(tr("Stop"), this)),
      take_name_(new QLineEdit("take-001", this)),
      take_button_(new QPushButton(tr("Record take"), this)),
      take_status_(new QLabel(this)),
      live_out_(new LiveOutControl(this)),
      live_feed_(new LiveFeedControl(this)),
      takes_folder_(QDir::homePath() + "/lumistage-takes") {
  qRegisterMetaType<lumistage::RunReport>();
  qRegisterMetaType<lumistage::PipelineSnapshot>();
  qRegisterMetaType<lumistage::PipelineView>();
  summary_->setWordWrap(true);
  summary_->setObjectName("pipeline_summary");
  source_->setObjectName("pipeline_source");
  table_->setObjectName("pipeline_nodes");
  source_->addItems({tr("Virtual studio (demo session)"), tr("Recorded session..."),
                     tr("Aravis cameras..."), tr("Nodes on the stage's PCs...")});
  source_->setItemData(kStageNodes,
                       tr("The nodes run on the camera PCs (lumistage-node --studio, or their "
                          "systemd unit); the studio listens for them with the keys they were "
                          "given"),
                       Qt::ToolTipRole);
  body_->setObjectName("pipeline_body");
  body_->addItem(tr("Standard body"), QString(bodyDetailName(BodyDetail::kStandard)));
  body_->addItem(tr("Fine body"), QString(bodyDetailName(BodyDetail::kFine)));
  body_->addItem(tr("Body file..."), QString());
  body_->setItemData(bodyFileItem(),
                     tr("A rigged human of your own (glTF/GLB, FBX, COLLADA, X), as --body FILE: "
                        "its joints are mapped onto the generic skeleton's, and the cameras paint "
                        "it"),
                     Qt::ToolTipRole);
  body_->setToolTip(
      tr("The body the studio and its nodes pose and refine. Standard (about 2000 vertices): "
         "four nodes and the studio on one PC keep up. Fine (about 4000): sharper views for twice "
         "the nodes' work, for nodes on PCs of their own, each started with --body fine. Or a "
         "rigged human from a file"));
  {
    const QString remembered = QSettings("Lumistage", "Studio").value("pipeline/body").toString();
    if (remembered == bodyDetailName(BodyDetail::kFine)) {
      setBody(BodyChoice{BodyDetail::kFine, {}});
    } else if (!remembered.isEmpty() && remembered != bodyDetailName(BodyDetail::kStandard) &&
               QFileInfo::exists(remembered)) {
      addBodyFile(remembered);  // checked when it was chosen; a file since damaged fails at start
    } else {
      setBody(BodyChoice{});
    }
  }
  shown_body_ = body_->currentIndex();
  connect(body_, &QComboBox::activated, this, [this](int index) {
    if (index != bodyFileItem()) return;
    const QString file = QFileDialog::getOpenFileName(
        this, tr("A rigged human"), QDir::homePath(),
        tr("Rigged meshes (*.glb *.gltf *.fbx *.dae *.x);;All files (*)"));
    const Status chosen = file.isEmpty() ? Status() : chooseBodyFile(file);
    if (!chosen.ok())
      QMessageBox::warning(this, tr("Body file"), QString::fromStdString(chosen.error()));
    if (file.isEmpty() || !chosen.ok()) body_->setCurrentIndex(shown_body_);
  });
  connect(body_, &QComboBox::currentIndexChanged, this, [this](int index) {
    if (index == bodyFileItem()) return;  // the dialog's turn: chosen, or back to the last
    shown_body_ = index;
    QSettings("Lumistage", "Studio").setValue("pipeline/body", body_->itemData(index).toString());
  });
  table_->setColumnCount(8);
  table_->setHorizontalHeaderLabels({tr("Node"), tr("State"), tr("Camera"), tr("fps"), tr("Frames"),
                                     tr("Dropped"), tr("Take"), tr("Last error")});
  table_->horizontalHeaderItem(6)->setToolTip(
      tr("The node's part of the take, then the free space of the disk it records takes to and "
         "how long that lasts at its cameras' rate (red under %1 minutes)")
          .arg(int(kLowDiskSeconds / 60)));
  table_->verticalHeader()->setVisible(false);
  table_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  table_->horizontalHeader()->setStretchLastSection(true);
  makeLiveTable(*table_);
  stages_->setColumnCount(2);
  stages_->setHorizontalHeaderLabels({tr("Stage"), tr("ms (mean)")});
  stages_->verticalHeader()->setVisible(false);
  stages_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  stages_->horizontalHeader()->setStretchLastSection(true);
  makeLiveTable(*stages_);
  stages_->setMaximumWidth(260);
  auto* buttons = new QHBoxLayout;
  buttons->addWidget(new QLabel(tr("Source:"), this));
  buttons->addWidget(source_);
  buttons->addWidget(body_);
  buttons->addWidget(start_button_);
  buttons->addWidget(stop_button_);
  buttons->addSpacing(24);
  buttons->addWidget(new QLabel(tr("Take:"), this));
  take_name_->setObjectName("take_name");
  take_name_->setToolTip(
      tr("The take's name: every node records its cameras' frames into "
         "TAKES/<take>/<node>/ on its own disk (letters, digits, '-', '_', '.')"));
  take_name_->setMaximumWidth(160);
  buttons->addWidget(take_name_);
  take_button_->setObjectName("record_take");
  take_button_->setEnabled(false);
  buttons->addWidget(take_button_);
  buttons->addStretch(1);
  auto* live = new QHBoxLayout;  // what goes out live: the skeleton, the view
  live->addWidget(live_out_);
  live->addSpacing(24);
  live->addWidget(live_feed_);
  live->addStretch(1);
  take_status_->setObjectName("take_status");
  take_status_->setWordWrap(true);
  take_status_->setTextInteractionFlags(Qt::TextSelectableByMouse);
  auto* layout = new QVBoxLayout(this);
  layout->addWidget(summary_);
  layout->addLayout(buttons);
  layout->addLayout(live);
  layout->addWidget(take_status_);
  auto* row = new QHBoxLayout;
  row->addWidget(table_, 1);
  row->addWidget(stages_);
  row->addWidget(view_);
  // 240x180 where there is room, down to 160x120 on a laptop's screen.
  view_->setMinimumSize(160, 120);
  view_->setMaximumSize(240, 180);
  view_->setAlignment(Qt::AlignCenter);
  view_->setStyleSheet("background: #202020; color: #aaa;");
  view_->setText(tr("the blended view"));
  layout->addLayout(row, 1);
  stop_button_->setEnabled(false);
  connect(start_button_, &QPushButton::clicked, this, &PipelinePanel::startChosen);
  connect(stop_button_, &QPushButton::clicked, this, &PipelinePanel::stop);
  connect(take_button_, &QPushButton::clicked, this, &PipelinePanel::toggleTake);
  connect(live_out_, &LiveOutControl::toggled, this, &PipelinePanel::applyLiveOut);
  connect(live_feed_, &LiveFeedControl::toggled, this, &PipelinePanel::applyLiveFeed);
}

PipelinePanel::~PipelinePanel() {
  stop();
}

void PipelinePanel::setBody(const BodyChoice& body) {
  if (!body.file.empty()) {
    addBodyFile(QString::fromStdString(body.file.string()));
    return;
  }
  body_->setCurrentIndex(body_->findData(QString(bodyDetailName(body.detail))));
}

BodyChoice PipelinePanel::body() const {
  const QString name = body_->itemData(shown_body_).toString();
  if (name == bodyDetailName(BodyDetail::kFine)) return BodyChoice{BodyDetail::kFine, {}};
  if (name.isEmpty() || name == bodyDetailName(BodyDetail::kStandard)) return BodyChoice{};
  return BodyChoice{BodyDetail::kStandard, name.toStdString()};
}

int PipelinePanel::bodyFileItem() const {
  return body_->count() - 1;
}

Status PipelinePanel::chooseBodyFile(const QString& file) {
  // Read in a child process, as lumistage body show reads it: a file that crashes Assimp (nested
  // too deep, damaged) costs the child, not the studio.
  if (const Status read = checkBodyFile(file.toStdString()); !read.ok()) return read;
  addBodyFile(file);
  return {};
}

void PipelinePanel::addBodyFile(const QString& file) {
  int index = body_->findData(file);
  if (index < 0) {
    index = bodyFileItem();  // before "Body file..."
    body_->insertItem(index, QFileInfo(file).fileName(), file);
    body_->setItemData(index, file, Qt::ToolTipRole);
  }
  body_->setCurrentIndex(index);
  shown_body_ = index;
  QSettings("Lumistage", "Studio").setValue("pipeline/body", file);
}

void PipelinePanel::startChosen() {
  LocalRunOptions options;
  options.replay = "memory";
  switch (source_->currentIndex()) {
    case kDemoSession:
      if (demo_session_.isEmpty()) {
        emit demoSessionWanted();  // the studio makes it, then starts
        return;
      }
      options.session = demo_session_.toStdString();
      break;
    case kRecordedSession: {
      const QString folder = QFileDialog::getExistingDirectory(this, tr("Recorded session to run"));
      if (folder.isEmpty()) return;
      options.session = folder.toStdString();
      break;
    }
    case kStageNodes: {
      const QString rig = QFileDialog::getOpenFileName(this, tr("The stage's rig file"), {},
                                                       tr("Rig files (*.yaml *.yml)"));
      if (rig.isEmpty()) return;
      const QString keys = QFileDialog::getExistingDirectory(
          this, tr("The key store the nodes were given (lumistage keys init)"));
      if (keys.isEmpty()) return;
      bool ok = false;
      const QString listen = QInputDialog::getText(
          this, tr("Nodes on the stage's PCs"),
          tr("Listen for the nodes at (their --studio, with this PC's name):"), QLineEdit::Normal,
          "tcp://*:5570", &ok);
      if (!ok || listen.isEmpty()) return;
      options.rig = rig.toStdString();
      options.keys = keys.toStdString();
      options.listen = listen.toStdString();
      break;
    }
    default: {  // kAravisCameras
      const QString rig = QFileDialog::getOpenFileName(this, tr("The cameras' rig file"), {},
                                                       tr("Rig files (*.yaml *.yml)"));
      if (rig.isEmpty()) return;
      bool ok = false;
      const QString address = QInputDialog::getText(
          this, tr("Aravis cameras"), tr("First camera's address (camera i at address + i):"),
          QLineEdit::Normal, "127.0.1.1", &ok);
      if (!ok || address.isEmpty()) return;
      options.rig = rig.toStdString();
      options.address = address.toStdString();
      break;
    }
  }
  start(options);
}

void PipelinePanel::start(LocalRunOptions options) {
  stop();
  // The source box says what runs, however it was started (here, or from the command line:
  // --pipeline SESSION, --listen).
  SourceEntry entry = kAravisCameras;
  if (!options.listen.empty())
    entry = kStageNodes;
  else if (!options.session.empty())
    entry =
        QString::fromStdString(options.session) == demo_session_ ? kDemoSession : kRecordedSession;
  source_->setCurrentIndex(entry);
  options.body = body();
  body_->setEnabled(false);  // the nodes pose it until they stop
  // Nodes started here record takes into the studio's folder; nodes on the stage's PCs into
  // their own (lumistage-node --takes).
  if (options.takes.empty() && options.listen.empty()) options.takes = takes_folder_.toStdString();
  thread_ = new QThread(this);
  worker_ = new PipelineWorker(std::move(options));
  worker_->moveToThread(thread_);
  if (view_data_) worker_->setView(*view_data_);
  connect(thread_, &QThread::started, worker_, &PipelineWorker::run);
  connect(worker_, &PipelineWorker::finished, thread_, &QThread::quit);
  // A pipeline that ends by itself (a session that is none, a key store missing) is cleaned up
  // as by Stop, and the buttons say so; stop() deletes the worker once its thread has ended, so
  // worker_ never points at a deleted one. (Not a later pipeline's: the generation tells.)
  connect(
      worker_, &PipelineWorker::finished, this,
      [this, generation = ++generation_] {
        if (generation == generation_) stop();
      },
      Qt::QueuedConnection);
  connect(worker_, &PipelineWorker::snapshot, this, &PipelinePanel::show);
  // (What a stopped pipeline's worker sent before it stopped, still queued, is not shown.)
  connect(worker_, &PipelineWorker::view, this, [this](const PipelineView& v) {
    if (thread_) emit view(v);
  });
  // The worker's last word (a recording that cannot be written, a node that exited) stays under
  // the figures, which the snapshots rewrite five times a second.
  notice_.clear();
  connect(worker_, &PipelineWorker::message, this, [this](const QString& text) {
    notice_ = text;
    summary_->setText(text.toHtmlEscaped());
  });
  connect(worker_, &PipelineWorker::recordingStarted, this,
          [this](const QString& partial, const QString& leftover) {
            if (thread_) emit recordingStarted(partial, leftover);
          });
  connect(worker_, &PipelineWorker::recordingEnded, this, &PipelinePanel::recordingEnded);
  connect(worker_, &PipelineWorker::takeRefused, this, &PipelinePanel::refuseTake);
  connect(worker_, &PipelineWorker::skeletonStreamFailed, live_out_,
          [this](const QString& why) { live_out_->failed(why); });
  connect(worker_, &PipelineWorker::viewFeedFailed, live_feed_,
          [this](const QString& why) { live_feed_->failed(why); });
  applyLiveOut();   // the live skeleton from the first frame, when its box is checked
  applyLiveFeed();  // the live view too
  start_button_->setEnabled(false);
  stop_button_->setEnabled(true);
  take_button_->setEnabled(true);
  summary_->setText(tr("Starting the nodes..."));
  thread_->start();
  emit started();
}

void PipelinePanel::stop() {
  if (!thread_) return;
  worker_->stop();
  thread_->quit();
  thread_->wait();
  delete worker_;  // its thread has ended
  delete thread_;
  thread_ = nullptr;
  worker_ = nullptr;
  start_button_->setEnabled(true);
  body_->setEnabled(true);
  stop_button_->setEnabled(false);
  take_button_->setEnabled(false);
  take_button_->setText(tr("Record take"));
  emit recordingEnded();  // whatever was recording is finished with its worker
  // This panel keeps the run's figures in words and clears what was live: the nodes (no longer
  // streaming), the blended view, a take under way (ended with the nodes).
  const RunReport& r = last_.report;
  summary_->setText(notice_.isEmpty()
                        ? tr("Stopped after %1 frames (%2 fps). Start runs the pipeline again.")
                              .arg(r.frames)
                              .arg(r.fps, 0, 'f', 1)
                        : notice_.toHtmlEscaped());
  table_->setRowCount(0);
  stages_->setRowCount(0);
  view_->clear();
  view_->setText(tr("the blended view"));
  if (last_.take_recording)
    take_status_->setText(tr("Take %1 ended with the pipeline.")
                              .arg(QString::fromStdString(last_.take.take).toHtmlEscaped()));
  take_name_->setEnabled(true);
  live_out_->showStream({}, 0);
  live_feed_->showFeed({}, 0, 0, {});
  // The panels forget the pipeline: the viewport its last image and body, the overlay its pose,
  // the camera health its nodes' reports (the source's own figures show again).
  last_ = PipelineSnapshot();
  emit snapshot(last_);
}

void PipelinePanel::setView(const ViewData& view) {
  view_data_ = view;
  if (worker_) worker_->setView(view);
}

void PipelinePanel::killNode(const QString& name) {
  if (worker_) worker_->killNode(name);
}

bool PipelinePanel::startRecording(const QString& file) {
  if (!worker_) return false;
  worker_->startRecording(file);
  return true;
}

void PipelinePanel::stopRecording() {
  if (worker_) worker_->stopRecording();
}

bool PipelinePanel::startTake(const QString& name) {
  if (!worker_) return false;
  worker_->startTake(name);
  return true;
}

void PipelinePanel::stopTake() {
  if (worker_) worker_->stopTake();
}

void PipelinePanel::toggleTake() {
  take_error_.clear();
  if (last_.take_recording) {
    stopTake();
    return;
  }
  const QString name = take_name_->text().trimmed();
  if (const Status named = checkTakeName(name.toStdString()); !named.ok()) {
    refuseTake(QString::fromStdString(named.error()));  // said at once, no round trip
    return;
  }
  startTake(name);
}

void PipelinePanel::refuseTake(const QString& reason) {
  take_error_ = tr("Cannot record the take: %1").arg(reason);
  take_status_->setText("<b style='color:#e33'>" + take_error_.toHtmlEscaped() + "</b>");
}

namespace {

// "take-007" -> "take-008": the name the next take is offered (digits at the end counted up,
// their width kept; "-2" added to a name without).
QString nextTakeName(const QString& name) {
  int digits = 0;
  while (digits < name.size() && name[name.size() - 1 - digits].isDigit()) ++digits;
  if (digits == 0) return name + "-2";
  const qlonglong number = name.right(digits).toLongLong() + 1;
  return name.left(name.size() - digits) + QString::number(number).rightJustified(digits, '0');
}

// A node's part of the take, for its row: sets written and dropped, or what went wrong; then the
// disk its takes go to: free space and how long it lasts at the cameras' rate.
QString takeCell(const NodeReport& n) {
  const TakeStatusData& t = n.take;
  QStringList parts;
  if (!t.error.empty()) {
    parts << QString::fromStdString(t.error);
  } else if (!t.take.empty()) {
    QString text = QObject::tr("%1 sets, %2 MB").arg(t.written).arg(t.bytes / 1e6, 0, 'f', 1);
    if (t.dropped > 0) text += QObject::tr(", %1 dropped").arg(t.dropped);
    if (t.finished) text += QObject::tr(", closed");
    parts << text;
  }
  if (t.free_bytes >= 0) {
    QString disk = QObject::tr("%1 free").arg(QString::fromStdString(bytesInWords(t.free_bytes)));
    if (n.take_seconds_left >= 0)
      disk += QObject::tr(" (%1 of takes)").arg(durationWords(n.take_seconds_left));
    parts << disk;
  }
  return parts.join(QStringLiteral(" · "));
}

// A stage of the report (as `lumistage run` and its JSON name it) in words, and what its time
// covers with its key (the tooltip).
std::pair<QString, QString> stageWords(const std::string& stage) {
  static const std::map<std::string, std::pair<const char*, const char*>> kStages = {
      {"mocap",
       {QT_TR_NOOP("motion capture"),
        QT_TR_NOOP("the skeleton's fit to the silhouettes, on its own thread")}},
      {"nodes_statistics_and_render",
       {QT_TR_NOOP("nodes"),
        QT_TR_NOOP("the pose sent to the frame done: the nodes' refinement statistics, the "
                   "studio's refinement, the nodes' images")}},
      {"refine",
       {QT_TR_NOOP("refinement"),
        QT_TR_NOOP("choosing every vertex's offset from the nodes' statistics")}},
      {"visibility",
       {QT_TR_NOOP("visibility"),
        QT_TR_NOOP("which cameras see each vertex of the refined mesh, sent with the offsets")}},
      {"combine",
       {QT_TR_NOOP("combine"), QT_TR_NOOP("the hull's agreement, when a frame is done")}},
      {"blend", {QT_TR_NOOP("blend"), QT_TR_NOOP("the nodes' images normalised and blended")}},
  };
  const QString key = QString::fromStdString(stage);
  const auto known = kStages.find(stage);
  if (known == kStages.end()) return {key, key};
  return {PipelinePanel::tr(known->second.first),
          QString("%1 (%2)").arg(PipelinePanel::tr(known->second.second), key)};
}

}  // namespace

QString pipelineSummary(const RunReport& r) {
  QString text =
      PipelinePanel::tr(
          "<b>%1 fps</b> (%13 since the start) &middot; latency %2 ms (median), %3 ms (95%) "
          "&middot; %4 frames, %5 dropped (%10 on arrival, to keep latency, %11 overtaken by newer "
          "frames, %12 without a node's image), %9 in flight &middot; %6 KB a frame per node "
          "against %7 KB raw &middot; %8 unknown nodes refused")
          .arg(r.fps_recent, 0, 'f', 1)
          .arg(r.latency_ms_p50, 0, 'f', 1)
          .arg(r.latency_ms_p95, 0, 'f', 1)
          .arg(r.frames)
          .arg(r.frames_dropped)
          .arg(r.node_bytes_per_frame / 1000, 0, 'f', 1)
          .arg(r.raw_bytes_per_frame_per_node / 1000, 0, 'f', 0)
          .arg(r.refusals)
          .arg(r.frames_in_flight)
          .arg(r.frames_refused)
          .arg(r.frames_overtaken)
          .arg(r.frames_unshown)
          .arg(r.fps, 0, 'f', 1);
  if (r.deadlines_following) {
    text += PipelinePanel::tr(
                " &middot; <span style='color:#c60'>waiting for a late node: its "
                "statistics up to %1 ms, its images up to %2 ms</span>")
                .arg(r.statistics_deadline_ms, 0, 'f', 0)
                .arg(r.image_deadline_ms, 0, 'f', 0);
  }
  return text;
}

void PipelinePanel::show(const PipelineSnapshot& s) {
  if (!thread_) return;  // still queued from a pipeline stopped since
  const bool was_recording = last_.take_recording;
  last_ = s;
  if (s.take_recording) take_error_.clear();
  take_button_->setText(s.take_recording ? tr("Stop take") : tr("Record take"));
  take_name_->setEnabled(!s.take_recording);
  live_out_->showStream(s.skeleton_target, s.skeleton_bundles);
  live_feed_->showFeed(s.feed_url, s.feed_sent, s.feed_dropped, s.feed_error);
  const QString takes = s.takes_folder.isEmpty()
                            ? tr("its own takes folder (lumistage-node --takes)")
                            : s.takes_folder.toHtmlEscaped();
  QString disk;  // the disk that fills first, of those that say
  if (const NodeReport* fullest = fullestTakeDisk(s.report)) {
    disk = tr("The fullest node's disk (%1) holds %2 of takes.")
               .arg(QString::fromStdString(fullest->name).toHtmlEscaped(),
                    durationWords(fullest->take_seconds_left));
    if (fullest->take_seconds_left < kLowDiskSeconds)
      disk = "<b style='color:#e33'>" + disk + "</b>";
  }
  if (!take_error_.isEmpty()) {
    // Kept until the next try: the refusal, not the last take's figures.
  } else if (s.take.take.empty()) {
    take_status_->setText(tr("Takes are recorded by every node into %1/&lt;take&gt;/&lt;node&gt;/; "
                             "lumistage session merge joins them. %2")
                              .arg(takes, disk));
  } else {
    const QString take = QString::fromStdString(s.take.take);
    const QString folder = takes + "/" + take.toHtmlEscaped();
    int64_t sets = 0, dropped = 0, closed = 0, failed = 0;
    for (const NodeReport& n : s.report.nodes) {
      if (n.take.take != s.take.take) continue;
      sets += n.take.written;
      dropped += n.take.dropped;
      closed += n.take.finished;
      failed += !n.take.error.empty();
    }
    QString text =
        s.take_recording
            ? tr("<b style='color:#e33'>&#9679; Recording take %1</b> from frame %2 into %3")
                  .arg(take.toHtmlEscaped())
                  .arg(s.take.first_frame)
                  .arg(folder)
            : tr("Take %1: frames %2 to %3 in %4 (%5 of %6 nodes closed)")
                  .arg(take.toHtmlEscaped())
                  .arg(s.take.first_frame)
                  .arg(s.take.last_frame)
                  .arg(folder)
                  .arg(closed)
                  .arg(s.report.nodes.size());
    text += tr(" &middot; %1 frame sets written, %2 dropped").arg(sets).arg(dropped);
    if (failed > 0)
      text += tr(" &middot; <b style='color:#e33'>%1 nodes failed: see the Take column</b>")
                  .arg(failed);
    if (!disk.isEmpty()) text += " &middot; " + disk;
    take_status_->setText(text);
    // The take just stopped: offer the next name.
    if (was_recording && !s.take_recording && take_name_->text() == take)
      take_name_->setText(nextTakeName(take));
  }
  const RunReport& r = s.report;
  if (!s.view.isNull())
    view_->setPixmap(QPixmap::fromImage(s.view).scaled(view_->size(), Qt::KeepAspectRatio));
  summary_->setText(pipelineSummary(r) +
                    (notice_.isEmpty() ? QString() : "<br>" + notice_.toHtmlEscaped()));
  stages_->setRowCount(static_cast<int>(r.stage_ms.size()));
  int stage_row = 0;
  for (const auto& [stage, ms] : r.stage_ms) {
    const auto [words, tooltip] = stageWords(stage);
    setLiveCell(*stages_, stage_row, 0, words);
    stages_->item(stage_row, 0)->setToolTip(tooltip);
    setLiveCell(*stages_, stage_row, 1, QString::number(ms, 'f', 2));
    ++stage_row;
  }
  int rows = 0;
  for (const NodeReport& n : r.nodes) rows += std::max<int>(1, static_cast<int>(n.cameras.size()));
  table_->setRowCount(rows);
  int row = 0;
  for (const NodeReport& n : r.nodes) {
    const bool gone = n.lost || s.exited.contains(QString::fromStdString(n.name));
    const QColor state_colour = gone ? QColor(0xe3, 0x33, 0x33) : QColor(0x2a, 0xa0, 0x2a);
    const int count = std::max<int>(1, static_cast<int>(n.cameras.size()));
    for (int k = 0; k < count; ++k, ++row) {
      const CameraHealth* c = k < static_cast<int>(n.cameras.size()) ? &n.cameras[k] : nullptr;
      setLiveCell(*table_, row, 0, k == 0 ? QString::fromStdString(n.name) : QString());
      setLiveCell(*table_, row, 1, k == 0 ? (gone ? tr("lost") : tr("streaming")) : QString(),
                  state_colour);
      setLiveCell(*table_, row, 2, c ? QString::fromStdString(c->camera) : QString());
      setLiveCell(*table_, row, 3, c ? QString::number(c->frame_rate_hz, 'f', 1) : QString());
      setLiveCell(*table_, row, 4, c ? QString::number(c->frames) : QString());
      setLiveCell(*table_, row, 5, c ? QString::number(c->dropped) : QString());
      const bool alarm = !n.take.error.empty() ||
                         (n.take_seconds_left >= 0 && n.take_seconds_left < kLowDiskSeconds);
      setLiveCell(*table_, row, 6, k == 0 ? takeCell(n) : QString(),
                  k == 0 && alarm ? QColor(0xe3, 0x33, 0x33) : palette().text().color());
      setLiveCell(*table_, row, 7, c ? QString::fromStdString(c->last_error) : QString());
    }
  }
  fitLiveColumns(*table_);
  fitLiveColumns(*stages_);
  emit snapshot(s);
}

}  // namespace lumistage
