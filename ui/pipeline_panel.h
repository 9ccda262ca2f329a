#pragma once

#include <QImage>
#include <QLabel>
#include <QMutex>
#include <QObject>
#include <QString>
#include <QStringList>
#include <QWidget>
#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "core/base/status.h"
#include "core/body/human_model.h"
#include "core/body/skinned_mesh.h"
#include "core/pipeline/local_run.h"
#include "core/render/view_recorder.h"
#include "ui/live_feed_control.h"
#include "ui/live_out_control.h"

class QComboBox;
class QLineEdit;
class QPushButton;
class QTableWidget;
class QThread;

namespace lumistage {

// The director's view as the studio blended it, with the body placed for that frame (the generic
// human posed, world coordinates): what the viewport draws, sent with every new blended frame.
struct PipelineView {
  QImage view;              // the blended image; null before the first frame
  int64_t view_frame = -1;  // its frame id
  int64_t pose_frame = -1;
  std::vector<Eigen::Vector3d> joints;       // the placed body's joints
  std::vector<int> parents;                  // per joint, -1 for the root
  std::shared_ptr<const TriangleMesh> mesh;  // the placed body's surface
  // The silhouettes the nodes keyed for pose_frame (StudioCoordinator::silhouettesOf); null when
  // the studio no longer holds them.
  std::shared_ptr<const std::vector<LowResSilhouette>> silhouettes;
};

// What the studio's panels see of the pipeline, five times a second: its figures, the newest view
// and the node processes that are gone.
struct PipelineSnapshot : PipelineView {
  RunReport report;
  QStringList exited;  // nodes whose process is no longer running
  double time_s = 0;   // since the pipeline started
  QString recording;   // the file the view is recorded to; empty: none
  int64_t recorded_frames = 0;
  RecordData take;  // the take asked of the nodes (name empty: none yet); theirs in report.nodes
  bool take_recording = false;
  QString takes_folder;  // where the nodes write their parts of a take
  // The skeleton's live stream (VMC over OSC): its receiver (empty: none) and frames sent.
  QString skeleton_target;
  int64_t skeleton_bundles = 0;
  // The view's live feed: its URL (empty: none), frames sent and dropped, why it stopped.
  QString feed_url;
  int64_t feed_sent = 0, feed_dropped = 0;
  QString feed_error;
};

// The pipeline panel's line of figures (rich text): the rate now and since the start, latency,
// frames and why they were dropped, frames in flight, bytes a node, unknown nodes refused; and,
// while the deadlines are stretched to a late node's answers, how long the studio waits for it.
QString pipelineSummary(const RunReport& report);

// Runs a LocalPipelineRun on its own thread (move to a QThread, call run()), reporting a snapshot
// five times a second, the view with every frame the studio blends (at the cameras' rate: a
// director dragging the camera sees video, not slides), and the node processes that exit. Commands
// from other threads (the view, killing a node) are queued and done between two slices of work.
class PipelineWorker : public QObject {
  Q_OBJECT

 public:
  explicit PipelineWorker(LocalRunOptions options) : options_(std::move(options)) {}
  void stop() { stop_ = true; }
  // Thread-safe: the view the nodes render from the next frame on.
  void setView(const ViewData& view);
  // Thread-safe: kills a node's process (as if unplugged).
  void killNode(const QString& name);
  // Thread-safe: records every blended image of the director's view (view 0) to `file` (.avi,
  // ViewRecorder) until stopRecording() or the pipeline stops; what went wrong comes as message().
  void startRecording(const QString& file);
  void stopRecording();
  // Thread-safe: every node records its cameras' frames as the take `name` (on its own disk,
  // StudioCoordinator::startTake) until stopTake(); why it cannot start comes as message().
  void startTake(const QString& name);
  void stopTake();
  // Thread-safe: streams the skeleton of every frame shown to `target` (LocalPipelineRun::
  // streamSkeleton) until stopStreamingSkeleton() or the pipeline stops (live_out_control.cpp).
  void streamSkeleton(const OscTarget& target);
  void stopStreamingSkeleton();
  // Thread-safe: sends the director's view live to `target` (LocalPipelineRun::feedView) until
  // stopFeedingView() or the pipeline stops (live_feed_control.cpp).
  void feedView(const FeedTarget& target);
  void stopFeedingView();

 public slots:
  void run();

 signals:
  void snapshot(lumistage::PipelineSnapshot snapshot);
  void view(lumistage::PipelineView view);
  void message(QString text);
  // The view's recording started: the file it is written to until it closes, and a partial file
  // of its name that an earlier recording left (empty: none).
  void recordingStarted(QString partial, QString leftover);
  void recordingEnded();                      // stopped, failed, or the pipeline stopped
  void takeRefused(QString reason);           // startTake(): why the take cannot start
  void skeletonStreamFailed(QString reason);  // streamSkeleton(): why it cannot stream
  void viewFeedFailed(QString reason);        // feedView(): why it cannot feed
  void finished();

 private:
  // Ends the view's recording, if any: closes the video (put in its place once it reads back
  // whole) and says how it went.
  void finishRecording(LocalPipelineRun& run);

  LocalRunOptions options_;
  std::atomic<bool> stop_{false};
  QMutex mutex_;
  std::vector<std::function<void(LocalPipelineRun&)>> commands_;  // guarded by mutex_
};

// The pipeline for technicians: frames a second, latency, per-stage times, frames in flight,
// bytes per node against the cameras' raw bytes, and every node and camera with its state; the
// source it runs on (the virtual studio's demo session, a recorded session, Aravis cameras);
// start and stop. Its snapshots feed the viewport, the health and overlay panels.
class PipelinePanel : public QWidget {
  Q_OBJECT

 public:
  explicit PipelinePanel(QWidget* parent = nullptr);
  ~PipelinePanel() override;

  // Starts the pipeline with the generic human chosen beside the source (options.body is set
  // from it), stopping any running one.
  void start(LocalRunOptions options);
  void stop();
  // The body the studio and the nodes it starts pose, from the next start on: a generic human or a
  // rigged human from a file; remembered between runs (the nodes on the stage's PCs must be
  // started with the same --body). setBody() of a file adds it to the choice unread.
  void setBody(const BodyChoice& body);
  BodyChoice body() const;
  // A rigged human from `file`, read and mapped onto the generic skeleton in a child process (as
  // the choice's "Body file..." does after its dialog): added to the choice and chosen, or failed
  // saying why (the file named), the choice left as it was.
  Status chooseBodyFile(const QString& file);
  bool running() const { return thread_ != nullptr; }
  const RunReport& lastReport() const { return last_.report; }
  const PipelineSnapshot& lastSnapshot() const { return last_; }
  QTableWidget* table() const { return table_; }
  QTableWidget* stageTable() const { return stages_; }
  void setView(const ViewData& view);
  void killNode(const QString& name);
  // Records the director's view while the pipeline runs (false, nothing done, when it does not).
  bool startRecording(const QString& file);
  void stopRecording();
  // Takes: the nodes record their cameras' frames (each to TAKES/<take>/<node>/); the Record take
  // button does the same. False when the pipeline is not running.
  bool startTake(const QString& name);
  void stopTake();
  // Where the nodes started from here record takes (default ~/lumistage-takes); from the next
  // start on.
  void setTakesFolder(const QString& folder) { takes_folder_ = folder; }
  const QString& takesFolder() const { return takes_folder_; }
  // The session "Virtual studio" runs (set by the studio once its demo session exists).
  void setDemoSession(const QString& folder) { demo_session_ = folder; }

 signals:
  void snapshot(const lumistage::PipelineSnapshot& snapshot);
  void view(const lumistage::PipelineView& view);  // every frame the studio blends
  void started();
  // A recording of the view started (PipelineWorker::recordingStarted).
  void recordingStarted(QString partial, QString leftover);
  // A recording of the view ended: asked to, a write failed, or the pipeline stopped.
  void recordingEnded();
  // Asks the studio to make the virtual studio's demo session (a long action with progress).
  void demoSessionWanted();

 private:
  void show(const PipelineSnapshot& snapshot);
  void startChosen();
  void toggleTake();
  void refuseTake(const QString& reason);
  // The live skeleton's box, checked or not, to the running pipeline (live_out_control.cpp).
  void applyLiveOut();
  // The live view's box, checked or not, to the running pipeline (live_feed_control.cpp).
  void applyLiveFeed();

  QLabel* summary_;
  QLabel* view_;  // the pipeline's output: the blended view
  QTableWidget* table_;
  QTableWidget* stages_;
  QComboBox* source_;
  QComboBox* body_;
  int shown_body_ = 0;  // the body's entry chosen (not "Body file...", while its dialog is open)
  int bodyFileItem() const;  // the last entry, "Body file..."
  void addBodyFile(const QString& file);
  QPushButton* start_button_;
  QPushButton* stop_button_;
  QLineEdit* take_name_;
  QPushButton* take_button_;
  QLabel* take_status_;
  LiveOutControl* live_out_;
  LiveFeedControl* live_feed_;
  QString take_error_;  // why the last take asked for could not start; shown until the next
  QString takes_folder_;
  QThread* thread_ = nullptr;
  PipelineWorker* worker_ = nullptr;
  int generation_ = 0;  // pipelines started, so that a late 'finished' stops no later one
  QString notice_;      // the worker's last message, shown under the figures
  PipelineSnapshot last_;
  std::optional<ViewData> view_data_;
  QString demo_session_;
};

}  // namespace lumistage

Q_DECLARE_METATYPE(lumistage::RunReport)
Q_DECLARE_METATYPE(lumistage::PipelineSnapshot)
Q_DECLARE_METATYPE(lumistage::PipelineView)
