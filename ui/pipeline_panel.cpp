#include "ui/pipeline_panel.h"

#include <QFileDialog>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QPixmap>
#include <QPushButton>
#include <QTableWidget>
#include <QThread>
#include <QVBoxLayout>
#include <exception>

namespace lumistage {

void PipelineWorker::run() {
  try {
    LocalPipelineRun pipeline(options_);
    emit message(tr("Pipeline running: %1 nodes, studio at %2")
                     .arg(pipeline.nodeNames().size())
                     .arg(QString::fromStdString(pipeline.studio().endpoint())));
    auto last = std::chrono::steady_clock::now();
    while (!stop_) {
      pipeline.runFor(std::chrono::milliseconds(100));
      for (const std::string& exit : pipeline.takeExits())
        emit message(QString::fromStdString(exit));
      if (std::chrono::steady_clock::now() - last > std::chrono::milliseconds(500)) {
        last = std::chrono::steady_clock::now();
        const BlendedImage& blended = pipeline.studio().lastImage();
        QImage view;
        if (!blended.rgba.empty()) {
          view = QImage(blended.rgba.data(), blended.width, blended.height, QImage::Format_RGBA8888)
                     .copy();
        }
        emit report(pipeline.studio().report(), view);
      }
    }
  } catch (const std::exception& e) {
    emit message(tr("Pipeline stopped: %1").arg(QString::fromStdString(e.what())));
  }
  emit finished();
}

PipelinePanel::PipelinePanel(QWidget* parent)
    : QWidget(parent),
      summary_(new QLabel(
          tr("Not running. Start runs the distributed pipeline on a recorded session: a node "
             "process per rig node, the studio's modules here."),
          this)),
      view_(new QLabel(this)),
      table_(new QTableWidget(this)),
      start_button_(new QPushButton(tr("Start on a session..."), this)),
      stop_button_(new QPushButton(tr("Stop"), this)) {
  qRegisterMetaType<lumistage::RunReport>();
  summary_->setWordWrap(true);
  table_->setColumnCount(7);
  table_->setHorizontalHeaderLabels({tr("Node"), tr("State"), tr("Camera"), tr("fps"), tr("Frames"),
                                     tr("Dropped"), tr("Last error")});
  table_->verticalHeader()->setVisible(false);
  table_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  table_->horizontalHeader()->setSectionResizeMode(QHeaderView::ResizeToContents);
  table_->horizontalHeader()->setStretchLastSection(true);
  auto* buttons = new QHBoxLayout;
  buttons->addWidget(start_button_);
  buttons->addWidget(stop_button_);
  buttons->addStretch(1);
  auto* layout = new QVBoxLayout(this);
  layout->addWidget(summary_);
  layout->addLayout(buttons);
  auto* row = new QHBoxLayout;
  row->addWidget(table_, 1);
  row->addWidget(view_);
  view_->setFixedSize(320, 240);
  view_->setAlignment(Qt::AlignCenter);
  view_->setStyleSheet("background: #202020; color: #aaa;");
  view_->setText(tr("the blended view"));
  layout->addLayout(row, 1);
  stop_button_->setEnabled(false);
  connect(start_button_, &QPushButton::clicked, this, &PipelinePanel::chooseSession);
  connect(stop_button_, &QPushButton::clicked, this, &PipelinePanel::stop);
}

PipelinePanel::~PipelinePanel() {
  stop();
}

void PipelinePanel::chooseSession() {
  const QString folder = QFileDialog::getExistingDirectory(this, tr("Recorded session to run"));
  if (folder.isEmpty()) return;
  LocalRunOptions options;
  options.session = folder.toStdString();
  options.replay = "memory";
  start(options);
}

void PipelinePanel::start(LocalRunOptions options) {
  stop();
  thread_ = new QThread(this);
  worker_ = new PipelineWorker(std::move(options));
  worker_->moveToThread(thread_);
  connect(thread_, &QThread::started, worker_, &PipelineWorker::run);
  connect(worker_, &PipelineWorker::finished, thread_, &QThread::quit);
  connect(thread_, &QThread::finished, worker_, &QObject::deleteLater);
  connect(worker_, &PipelineWorker::report, this, &PipelinePanel::show);
  connect(worker_, &PipelineWorker::message, summary_, &QLabel::setText);
  start_button_->setEnabled(false);
  stop_button_->setEnabled(true);
  summary_->setText(tr("Starting the nodes..."));
  thread_->start();
}

void PipelinePanel::stop() {
  if (!thread_) return;
  worker_->stop();  // alive until its thread finishes
  thread_->quit();
  thread_->wait();
  delete thread_;
  thread_ = nullptr;
  worker_ = nullptr;
  start_button_->setEnabled(true);
  stop_button_->setEnabled(false);
}

void PipelinePanel::show(const RunReport& r, const QImage& view) {
  last_ = r;
  if (!view.isNull()) view_->setPixmap(QPixmap::fromImage(view));
  summary_->setText(tr("<b>%1 fps</b> &middot; latency %2 ms (median), %3 ms (95%) &middot; %4 "
                       "frames, %5 dropped "
                       "&middot; %6 KB a frame per node against %7 KB raw &middot; %8 refused")
                        .arg(r.fps, 0, 'f', 1)
                        .arg(r.latency_ms_p50, 0, 'f', 1)
                        .arg(r.latency_ms_p95, 0, 'f', 1)
                        .arg(r.frames)
                        .arg(r.frames_dropped)
                        .arg(r.node_bytes_per_frame / 1000, 0, 'f', 1)
                        .arg(r.raw_bytes_per_frame_per_node / 1000, 0, 'f', 0)
                        .arg(r.refusals));
  int rows = 0;
  for (const NodeReport& n : r.nodes) rows += std::max<int>(1, static_cast<int>(n.cameras.size()));
  table_->setRowCount(rows);
  int row = 0;
  for (const NodeReport& n : r.nodes) {
    const QColor state_colour = n.lost ? QColor(0xe3, 0x33, 0x33) : QColor(0x2a, 0xa0, 0x2a);
    const int count = std::max<int>(1, static_cast<int>(n.cameras.size()));
    for (int k = 0; k < count; ++k, ++row) {
      auto set = [&](int column, const QString& text) {
        table_->setItem(row, column, new QTableWidgetItem(text));
      };
      set(0, k == 0 ? QString::fromStdString(n.name) : QString());
      set(1, k == 0 ? (n.lost ? tr("lost") : tr("streaming")) : QString());
      table_->item(row, 1)->setForeground(state_colour);
      if (k < static_cast<int>(n.cameras.size())) {
        const CameraHealth& c = n.cameras[k];
        set(2, QString::fromStdString(c.camera));
        set(3, QString::number(c.frame_rate_hz, 'f', 1));
        set(4, QString::number(c.frames));
        set(5, QString::number(c.dropped));
        set(6, QString::fromStdString(c.last_error));
      }
    }
  }
}

}  // namespace lumistage
