// The pipeline's worker thread (PipelineWorker, pipeline_panel.h): runs the distributed pipeline
// on its own thread for the Pipeline panel, records the view and takes, and hands the panel a
// snapshot of the figures.
#include <QMutexLocker>
#include <exception>

#include "core/body/human_model.h"
#include "core/net/posed_body.h"
#include "ui/pipeline_panel.h"

namespace lumistage {

void PipelineWorker::setView(const ViewData& view) {
  QMutexLocker lock(&mutex_);
  commands_.push_back([view](LocalPipelineRun& run) { run.studio().setView(view); });
}

void PipelineWorker::killNode(const QString& name) {
  QMutexLocker lock(&mutex_);
  commands_.push_back([name](LocalPipelineRun& run) { run.killNode(name.toStdString()); });
}

void PipelineWorker::startRecording(const QString& file) {
  QMutexLocker lock(&mutex_);
  commands_.push_back([this, file](LocalPipelineRun& run) {
    try {
      run.recordView(file.toStdString(), [this](const std::string& error) {
        emit message(tr("Recording stopped: %1").arg(QString::fromStdString(error)));
      });
    } catch (const std::exception& e) {
      emit message(tr("Cannot record the view: %1").arg(QString::fromStdString(e.what())));
      emit recordingEnded();
      return;
    }
    emit message(tr("Recording the view to %1").arg(file));
    if (const ViewRecorder* recorder = run.viewRecording()) {
      if (const std::string notice = recorder->leftoverNotice(); !notice.empty())
        emit message(QString::fromStdString(notice));
      emit recordingStarted(QString::fromStdString(recorder->partialFile().string()),
                            QString::fromStdString(recorder->leftover().string()));
    }
  });
}

void PipelineWorker::stopRecording() {
  QMutexLocker lock(&mutex_);
  commands_.push_back([this](LocalPipelineRun& run) { finishRecording(run); });
}

void PipelineWorker::finishRecording(LocalPipelineRun& run) {
  const bool failed_before = run.viewRecordingFailed();
  const std::unique_ptr<ViewRecorder> recorder = run.stopRecordingView();
  if (!recorder) return;
  if (const Status recorded = recorder->status(); !recorded.ok()) {
    emit message(
        tr("Recording of the view failed: %1").arg(QString::fromStdString(recorded.error())));
  } else if (recorder->framesWritten() > 0 || !failed_before) {
    emit message(tr("Recorded %1 frames of the view to %2%3")
                     .arg(recorder->framesWritten())
                     .arg(QString::fromStdString(recorder->file().string()))
                     .arg(failed_before ? tr(" (stopped early: see above)") : QString()));
  }
  emit recordingEnded();
}

void PipelineWorker::startTake(const QString& name) {
  QMutexLocker lock(&mutex_);
  commands_.push_back([this, name](LocalPipelineRun& run) {
    const Status started = run.studio().startTake(name.toStdString());
    if (!started.ok()) emit takeRefused(QString::fromStdString(started.error()));
  });
}

void PipelineWorker::stopTake() {
  QMutexLocker lock(&mutex_);
  commands_.push_back([](LocalPipelineRun& run) { run.studio().stopTake(); });
}

void PipelineWorker::run() {
  try {
    LocalPipelineRun pipeline(options_);
    emit message((pipeline.nodesElsewhere()
                      ? tr("Studio at %2, listening for the rig's %1 nodes on the stage's PCs")
                      : tr("Pipeline running: %1 nodes, studio at %2"))
                     .arg(pipeline.nodeNames().size())
                     .arg(QString::fromStdString(pipeline.studio().endpoint())));
    // The body the studio places, to draw over the views (as the nodes pose it).
    const SkinnedMesh& human = pipeline.body();
    Pose pose;
    std::vector<Eigen::Affine3f> transforms;
    const auto start = std::chrono::steady_clock::now();
    auto last = start;
    PipelineView shown;  // the newest view, with the body placed for its frame
    for (const Joint& j : human.skeleton.joints()) shown.parents.push_back(j.parent);
    // Places the body for a pose (of frame `pose_frame`) unless it is there already.
    auto placeBody = [&](const PoseData& pose_data, int64_t pose_frame) {
      if (pose_frame == shown.pose_frame ||
          pose_data.angles.size() != size_t(3) * human.skeleton.jointCount())
        return;
      shown.pose_frame = pose_frame;
      auto mesh = std::make_shared<TriangleMesh>();
      posedBodyMesh(human, pose_data, pose, transforms, mesh->positions, mesh->normals);
      human.skeleton.jointPositions(pose, shown.joints);
      for (Eigen::Vector3d& joint : shown.joints) joint *= pose_data.scale;
      mesh->triangles = human.rest.triangles;
      shown.mesh = std::move(mesh);
    };
    while (!stop_) {
      bool acted = false;
      {
        std::vector<std::function<void(LocalPipelineRun&)>> commands;
        {
          QMutexLocker lock(&mutex_);
          commands.swap(commands_);
        }
        for (auto& command : commands) command(pipeline);
        acted = !commands.empty();
      }
      // Short slices: a blended frame goes to the viewport within 10 ms.
      if (!acted) pipeline.runFor(std::chrono::milliseconds(10));
      for (const std::string& exit : pipeline.takeExits())
        emit message(QString::fromStdString(exit));
      // Every new blended frame to the viewport, with the skeleton and mesh of its own frame (the
      // newest pose runs a few frames ahead of the newest image).
      const BlendedImage& blended = pipeline.studio().lastImage();
      if (!blended.rgba.empty() && blended.frame_id != shown.view_frame) {
        shown.view = QImage(blended.rgba.data(), blended.width, blended.height,
                            QImage::Format_RGBA8888_Premultiplied)
                         .copy();
        shown.view_frame = blended.frame_id;
        placeBody(blended.pose, blended.frame_id);
        emit view(shown);
      }
      const auto now = std::chrono::steady_clock::now();
      // Five times a second, and at once after a command (a killed node shows at once).
      if (!acted && now - last < std::chrono::milliseconds(200)) continue;
      last = now;
      // Before the first image: the newest pose.
      if (shown.view_frame < 0)
        placeBody(pipeline.studio().lastPose(), pipeline.studio().lastPoseFrame());
      PipelineSnapshot s;
      static_cast<PipelineView&>(s) = shown;
      if (const auto* keyed = pipeline.studio().silhouettesOf(shown.pose_frame))
        s.silhouettes = std::make_shared<const std::vector<LowResSilhouette>>(*keyed);
      s.report = pipeline.studio().report();
      s.time_s = std::chrono::duration<double>(now - start).count();
      for (const std::string& name : pipeline.nodeNames()) {
        if (!pipeline.nodeRunning(name)) s.exited << QString::fromStdString(name);
      }
      if (pipeline.viewRecordingFailed()) finishRecording(pipeline);
      if (const ViewRecorder* recorder = pipeline.viewRecording()) {
        s.recording = QString::fromStdString(recorder->file().string());
        s.recorded_frames = recorder->framesWritten();
      }
      s.take = pipeline.studio().take();
      s.take_recording = pipeline.studio().recordingTake();
      s.takes_folder = QString::fromStdString(options_.takes.string());
      if (const VmcSender* sender = pipeline.skeletonStream()) {
        s.skeleton_target = QString::fromStdString(sender->target().text());
        s.skeleton_bundles = sender->bundlesSent();
      }
      if (const VideoFeed* feed = pipeline.viewFeed()) {
        s.feed_url = QString::fromStdString(feed->target().url);
        s.feed_sent = feed->framesSent();
        s.feed_dropped = feed->framesDropped();
        s.feed_error = QString::fromStdString(feed->status().error());
      }
      emit snapshot(s);
    }
    finishRecording(pipeline);  // a recording under way ends with the pipeline
  } catch (const std::exception& e) {
    emit message(tr("Pipeline stopped: %1").arg(QString::fromStdString(e.what())));
  }
  emit finished();
}

}  // namespace lumistage
