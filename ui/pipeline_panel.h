#pragma once

#include <QImage>
#include <QLabel>
#include <QObject>
#include <QString>
#include <QWidget>
#include <atomic>

#include "core/pipeline/local_run.h"

class QPushButton;
class QTableWidget;
class QThread;

namespace lumistage {

// Runs a LocalPipelineRun on its own thread (move to a QThread, call run()), reporting its figures
// twice a second and the node processes that exit.
class PipelineWorker : public QObject {
  Q_OBJECT

 public:
  explicit PipelineWorker(LocalRunOptions options) : options_(std::move(options)) {}
  void stop() { stop_ = true; }

 public slots:
  void run();

 signals:
  void report(lumistage::RunReport report, QImage view);
  void message(QString text);
  void finished();

 private:
  LocalRunOptions options_;
  std::atomic<bool> stop_{false};
};

// The pipeline for technicians: frames a second, latency, bytes per node against the cameras'
// raw bytes, and every node and camera with its state (streaming or lost, in colour), rate,
// drops and last error. A killed node turns red within about a second.
class PipelinePanel : public QWidget {
  Q_OBJECT

 public:
  explicit PipelinePanel(QWidget* parent = nullptr);
  ~PipelinePanel() override;

  void start(LocalRunOptions options);
  void stop();
  bool running() const { return thread_ != nullptr; }
  const RunReport& lastReport() const { return last_; }
  QTableWidget* table() const { return table_; }

 private:
  void show(const RunReport& report, const QImage& view);
  void chooseSession();

  QLabel* summary_;
  QLabel* view_;  // the pipeline's output: the blended view
  QTableWidget* table_;
  QPushButton* start_button_;
  QPushButton* stop_button_;
  QThread* thread_ = nullptr;
  PipelineWorker* worker_ = nullptr;
  RunReport last_;
};

}  // namespace lumistage

Q_DECLARE_METATYPE(lumistage::RunReport)
