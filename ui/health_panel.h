#pragma once

#include <QElapsedTimer>
#include <QImage>
#include <QPixmap>
#include <QVector>
#include <QWidget>

#include "core/geometry/rig.h"
#include "core/pipeline/camera_health.h"
#include "ui/pipeline_panel.h"
#include "ui/source_worker.h"

class QTableWidget;
class QLabel;

namespace lumistage {

// A plot of a camera's recent frame rate and its node's answer time.
class HistoryPlot : public QWidget {
  Q_OBJECT

 public:
  explicit HistoryPlot(const HealthHistory* history, QWidget* parent = nullptr);
  void setCamera(const QString& camera);

 protected:
  void paintEvent(QPaintEvent* event) override;

 private:
  const HealthHistory* history_;
  QString camera_;
};

// Camera health for technicians: every camera with its node, a live thumbnail, its state
// (streaming / late / lost) in colour and its problem in words, frame rate, drops, how long its
// node takes to answer the studio, bytes a frame, exposure and gain where the camera reports them;
// below, the history of the selected camera's frame rate and its node's answer time. States come
// from the pipeline's node reports (a node whose process exits is lost at once; a silent one late
// after 500 ms, lost after a second) or, without a pipeline, from the live source's frames.
class HealthPanel : public QWidget {
  Q_OBJECT

 public:
  explicit HealthPanel(QWidget* parent = nullptr);

  void setRig(const Rig& rig);
  HealthVerdict verdict(int camera) const;  // now
  QTableWidget* table() const { return table_; }
  const HealthHistory& history() const { return history_; }
  HistoryPlot* plot() const { return plot_; }

 public slots:
  void showSnapshot(const lumistage::PipelineSnapshot& snapshot);
  void showFrame(int camera, const QImage& preview, qint64 frame_id);
  void showStatus(const QVector<lumistage::CameraStatus>& cameras);

 private:
  struct Row {
    QString camera, node;
    QPixmap thumbnail;
    bool from_pipeline = false;
    QElapsedTimer since_report;  // since the pipeline report or the source frame below
    double silent_ms_at_report = -1;
    bool exited = false;
    double fps = 0, answer_ms = -1, bytes_per_frame = -1;  // answer: its node's (NodeReport)
    int64_t dropped = 0, dropped_recently = 0;
    QElapsedTimer since_drop;  // valid once a frame was dropped
    QString last_error;
    QString key;  // how its node keys it (CameraHealth::key), from the pipeline's report
    bool has_frame = false;
    QElapsedTimer since_frame, since_thumbnail;
  };
  void refresh();
  HealthInput input(const Row& row) const;
  static void setDropped(Row& row, int64_t dropped);

  QTableWidget* table_;
  HistoryPlot* plot_;
  QLabel* legend_;
  QVector<Row> rows_;
  HealthHistory history_;
  QElapsedTimer clock_;
};

}  // namespace lumistage
