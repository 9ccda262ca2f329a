#include "ui/health_panel.h"

#include <QHeaderView>
#include <QLabel>
#include <QPainter>
#include <QPainterPath>
#include <QTableWidget>
#include <QTimer>
#include <QVBoxLayout>
#include <algorithm>

#include "core/net/message_codec.h"
#include "ui/live_table.h"

namespace lumistage {

namespace {

QColor stateColour(HealthState state) {
  switch (state) {
    case HealthState::kStreaming:
      return QColor(0x2a, 0xb0, 0x2a);
    case HealthState::kLate:
      return QColor(0xe0, 0x90, 0x00);
    case HealthState::kLost:
      return QColor(0xe3, 0x33, 0x33);
    case HealthState::kUnknown:
      break;
  }
  return QColor(0x88, 0x88, 0x88);
}

enum Column { kCamera, kState, kProblem, kFps, kDropped, kAnswer, kBytes, kExposure };

}  // namespace

HistoryPlot::HistoryPlot(const HealthHistory* history, QWidget* parent)
    : QWidget(parent), history_(history) {
  setMinimumHeight(60);  // the window fits a 1366x768 laptop screen
}

void HistoryPlot::setCamera(const QString& camera) {
  camera_ = camera;
  update();
}

void HistoryPlot::paintEvent(QPaintEvent*) {
  QPainter painter(this);
  painter.setRenderHint(QPainter::Antialiasing);
  painter.fillRect(rect(), QColor(28, 30, 34));
  const QRectF area = QRectF(rect()).adjusted(40, 16, -46, -18);
  painter.setPen(QColor(70, 74, 80));
  painter.drawRect(area);
  painter.setPen(QColor(200, 200, 200));
  painter.drawText(QPointF(6, 12), camera_.isEmpty()
                                       ? tr("select a camera")
                                       : tr("%1: frame rate (green, fps) and "
                                            "its node's answer (blue, ms), last minute")
                                             .arg(camera_));
  if (camera_.isEmpty()) return;
  const auto& fps = history_->samples(camera_.toStdString() + "/fps");
  const auto& answer = history_->samples(camera_.toStdString() + "/answer");
  double t_end = 0;
  if (!fps.empty()) t_end = fps.back().time_s;
  if (!answer.empty()) t_end = std::max(t_end, answer.back().time_s);
  const double t_start = t_end - 60;
  auto curve = [&](const std::deque<HealthHistory::Sample>& s, double max, const QColor& c,
                   bool right_axis) {
    double top = max;
    for (const auto& p : s) top = std::max(top, p.value * 1.1);
    QPainterPath path;
    bool first = true;
    for (const auto& p : s) {
      if (p.time_s < t_start) continue;
      const QPointF q(area.left() + (p.time_s - t_start) / 60 * area.width(),
                      area.bottom() - std::max(0.0, p.value) / top * area.height());
      if (first) {
        path.moveTo(q);
        first = false;
      } else {
        path.lineTo(q);
      }
    }
    painter.setPen(QPen(c, 1.8));
    painter.setBrush(Qt::NoBrush);
    painter.drawPath(path);
    painter.drawText(
        right_axis ? QPointF(area.right() + 4, area.top() + 10) : QPointF(4, area.top() + 10),
        QString::number(top, 'f', 0));
  };
  curve(fps, 30, QColor(60, 200, 80), false);
  curve(answer, 100, QColor(80, 150, 255), true);
}

HealthPanel::HealthPanel(QWidget* parent)
    : QWidget(parent),
      table_(new QTableWidget(this)),
      plot_(new HistoryPlot(&history_, this)),
      legend_(new QLabel(this)) {
  clock_.start();
  table_->setColumnCount(8);
  table_->setHorizontalHeaderLabels({tr("Camera"), tr("State"), tr("Problem"), tr("fps"),
                                     tr("Drops"), tr("Node ms"), tr("KB/fr"), tr("Exp/gain")});
  table_->horizontalHeaderItem(kAnswer)->setToolTip(
      tr("How long its node takes to answer the studio, ms (median of recent frames): the pose to "
         "its refinement statistics plus the offsets to its image. A node slower than the others "
         "(an overloaded PC, a slow link) shows here before it misses frames"));
  table_->horizontalHeaderItem(kBytes)->setToolTip(tr("Bytes the node sends a frame, per camera"));
  table_->horizontalHeaderItem(kExposure)->setToolTip(
      tr("Exposure and gain, where the camera reports them"));
  table_->verticalHeader()->setVisible(false);
  table_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  table_->setSelectionBehavior(QAbstractItemView::SelectRows);
  table_->setSelectionMode(QAbstractItemView::SingleSelection);
  table_->setIconSize(QSize(48, 36));
  table_->verticalHeader()->setDefaultSectionSize(40);
  table_->horizontalHeader()->setMinimumSectionSize(40);
  makeLiveTable(*table_, kProblem);
  setMinimumWidth(600);  // the problem in words must be readable
  legend_->setText(
      tr("<span style='color:#2ab02a'>&#9679; streaming</span> &nbsp; "
         "<span style='color:#e09000'>&#9679; late: nothing for 0.5 s, slow or dropping</span> "
         "&nbsp; <span style='color:#e33333'>&#9679; lost: nothing for 1 s, or its node "
         "stopped</span>"));
  legend_->setWordWrap(true);
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(2, 2, 2, 2);
  layout->addWidget(legend_);
  layout->addWidget(table_, 3);
  layout->addWidget(plot_, 1);
  connect(table_, &QTableWidget::currentCellChanged, this, [this](int row) {
    if (row >= 0 && row < rows_.size()) plot_->setCamera(rows_[row].camera);
  });
  auto* timer = new QTimer(this);  // states age even when no report arrives
  connect(timer, &QTimer::timeout, this, &HealthPanel::refresh);
  timer->start(100);
}

void HealthPanel::setRig(const Rig& rig) {
  rows_.clear();
  history_.clear();
  for (const Camera& c : rig.cameras()) {
    Row row;
    row.camera = QString::fromStdString(c.name());
    row.node = QString::fromStdString(c.node());
    rows_.push_back(row);
  }
  table_->setRowCount(rows_.size());
  for (int r = 0; r < rows_.size(); ++r) {
    for (int c = 0; c < table_->columnCount(); ++c) table_->setItem(r, c, new QTableWidgetItem);
    table_->item(r, kCamera)->setText(rows_[r].camera + "\n" + rows_[r].node);
  }
  if (!rows_.isEmpty()) {
    table_->setCurrentCell(0, 0);
    plot_->setCamera(rows_[0].camera);
  }
  refresh();
}

void HealthPanel::showSnapshot(const PipelineSnapshot& s) {
  const double t = clock_.elapsed() / 1000.0;
  if (s.report.nodes.empty()) {  // no pipeline (stopped): the source's figures are the cameras'
    for (Row& row : rows_) row.from_pipeline = false;
    refresh();
    return;
  }
  for (const NodeReport& node : s.report.nodes) {
    const QString node_name = QString::fromStdString(node.name);
    const bool exited = s.exited.contains(node_name);
    for (Row& row : rows_) {
      if (row.node != node_name) continue;
      row.from_pipeline = true;
      row.since_report.restart();
      row.silent_ms_at_report = node.silent_ms;
      row.exited = exited;
      // A node that is gone answers nothing: no figure rather than its last.
      row.answer_ms = !exited && !node.lost && node.statistics_ms >= 0 && node.image_ms >= 0
                          ? node.statistics_ms + node.image_ms
                          : -1;
      row.bytes_per_frame =
          node.bytes_per_frame >= 0
              ? node.bytes_per_frame / double(std::max<size_t>(1, node.cameras.size()))
              : -1;
      for (const CameraHealth& c : node.cameras) {
        if (QString::fromStdString(c.camera) != row.camera) continue;
        row.fps = c.frame_rate_hz;
        setDropped(row, c.dropped);
        row.last_error = QString::fromStdString(c.last_error);
        row.key = QString::fromStdString(c.key);
      }
      if (exited || node.lost) row.fps = 0;
      history_.add(row.camera.toStdString() + "/fps", t, row.fps);
      if (!exited && !node.lost && row.answer_ms >= 0)
        history_.add(row.camera.toStdString() + "/answer", t, row.answer_ms);
    }
  }
  refresh();
  plot_->update();
}

void HealthPanel::showFrame(int camera, const QImage& preview, qint64) {
  if (camera < 0 || camera >= rows_.size()) return;
  Row& row = rows_[camera];
  row.has_frame = true;
  row.since_frame.restart();
  if (!row.since_thumbnail.isValid() || row.since_thumbnail.elapsed() > 1000) {
    row.since_thumbnail.restart();  // a live thumbnail once a second
    row.thumbnail = QPixmap::fromImage(preview.scaled(48, 36, Qt::KeepAspectRatio));
    table_->item(camera, kCamera)->setIcon(row.thumbnail);
  }
}

void HealthPanel::showStatus(const QVector<CameraStatus>& cameras) {
  const double t = clock_.elapsed() / 1000.0;
  for (int c = 0; c < cameras.size() && c < rows_.size(); ++c) {
    Row& row = rows_[c];
    if (row.from_pipeline) continue;  // the pipeline's view of the camera wins
    row.fps = cameras[c].frame_rate_hz;
    setDropped(row, cameras[c].dropped);
    row.last_error = cameras[c].last_error;
    history_.add(row.camera.toStdString() + "/fps", t, row.fps);
  }
  refresh();
}

HealthInput HealthPanel::input(const Row& row) const {
  HealthInput in;
  in.frame_rate_hz = row.fps;
  in.last_error = row.last_error.toStdString();
  // Drops show for two seconds after they happen.
  in.dropped_recently =
      row.since_drop.isValid() && row.since_drop.elapsed() < 2000 ? row.dropped_recently : 0;
  if (row.from_pipeline) {
    in.process_exited = row.exited;
    in.silent_ms =
        row.silent_ms_at_report < 0 ? -1 : row.silent_ms_at_report + row.since_report.elapsed();
  } else if (row.has_frame) {
    in.silent_ms = row.since_frame.elapsed();
  }
  return in;
}

void HealthPanel::setDropped(Row& row, int64_t dropped) {
  if (dropped > row.dropped && row.dropped >= 0) {
    row.dropped_recently = dropped - row.dropped;
    row.since_drop.restart();
  }
  row.dropped = dropped;
}

HealthVerdict HealthPanel::verdict(int camera) const {
  return classifyHealth(input(rows_.at(camera)));
}

void HealthPanel::refresh() {
  for (int r = 0; r < rows_.size(); ++r) {
    Row& row = rows_[r];
    const HealthVerdict v = classifyHealth(input(row));
    const QColor colour = stateColour(v.state);
    setLiveCell(*table_, r, kState, QString::fromUtf8(healthStateName(v.state)), Qt::white);
    table_->item(r, kState)->setBackground(colour);
    // A camera keyed other than on green (a stage without a green screen: from the session's
    // masks, or on its clean plate) says so.
    QString words = QString::fromStdString(v.words);
    if (!row.key.isEmpty() && row.key != QLatin1String(kKeyedOnGreen)) words += "; " + row.key;
    setLiveCell(*table_, r, kProblem, words,
                v.state == HealthState::kStreaming ? palette().text().color() : colour);
    setLiveCell(*table_, r, kFps, QString::number(row.fps, 'f', 1));
    setLiveCell(*table_, r, kDropped, QString::number(row.dropped));
    setLiveCell(*table_, r, kAnswer,
                row.answer_ms >= 0 ? QString::number(row.answer_ms, 'f', 1) : QString("-"));
    setLiveCell(*table_, r, kBytes,
                row.bytes_per_frame >= 0 ? QString::number(row.bytes_per_frame / 1000, 'f', 1)
                                         : QString("-"));
    setLiveCell(*table_, r, kExposure, "-");
  }
  fitLiveColumns(*table_);
}

}  // namespace lumistage
