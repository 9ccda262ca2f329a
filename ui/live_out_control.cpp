#include "ui/live_out_control.h"

#include <QMutexLocker>
#include <exception>

#include "core/base/error.h"
#include "ui/pipeline_panel.h"

namespace lumistage {

namespace {

LiveTargetRowSpec skeletonRow() {
  LiveTargetRowSpec spec;
  spec.label = QObject::tr("Live skeleton to");
  spec.box_name = "live_skeleton";
  spec.box_tip =
      QObject::tr(
          "Streams the tracked skeleton of every frame shown over OSC in the VMC protocol, as "
          "lumistage run --osc: VSeeFace, EVMC4U for Unity, VMC4UE for Unreal and the Blender "
          "add-ons receive it (their usual port is %1)")
          .arg(VmcSender::kDefaultPort);
  spec.target_name = "live_skeleton_target";
  spec.target_tip = QObject::tr("The receiver: HOST:PORT (IPv6 in brackets)");
  spec.default_target = QString("127.0.0.1:%1").arg(VmcSender::kDefaultPort);
  spec.target_min_width = 150;
  spec.target_max_width = 170;
  spec.setting = "pipeline/osc";
  spec.status_name = "live_skeleton_status";
  return spec;
}

}  // namespace

LiveOutControl::LiveOutControl(QWidget* parent) : LiveTargetRow(skeletonRow(), parent) {}

std::optional<OscTarget> LiveOutControl::wantedTarget() {
  return LiveTargetRow::wantedTarget(parseOscTarget, tr("expected HOST:PORT"));
}

void LiveOutControl::showStream(const QString& target, int64_t bundles) {
  if (target.isEmpty()) {
    showStatus({});
    return;
  }
  showStatus(tr("%1 frames sent").arg(bundles),
             tr("VMC bundles sent to %1, one a frame shown").arg(target));
}

// The pipeline worker's side of it, here beside the control.
void PipelineWorker::streamSkeleton(const OscTarget& target) {
  QMutexLocker lock(&mutex_);
  commands_.push_back([this, target](LocalPipelineRun& run) {
    const QString where = QString::fromStdString(target.text());
    try {
      run.streamSkeleton(target);
    } catch (const std::exception& e) {
      emit skeletonStreamFailed(QString::fromStdString(e.what()));
      emit message(tr("Cannot stream the skeleton: %1").arg(QString::fromStdString(e.what())));
      return;
    }
    emit message(tr("Streaming the skeleton to %1 (VMC over OSC)").arg(where));
  });
}

void PipelineWorker::stopStreamingSkeleton() {
  QMutexLocker lock(&mutex_);
  commands_.push_back([this](LocalPipelineRun& run) {
    if (const VmcSender* sender = run.skeletonStream()) {
      emit message(tr("Stopped the skeleton's stream to %1 after %2 frames")
                       .arg(QString::fromStdString(sender->target().text()))
                       .arg(sender->bundlesSent()));
    }
    run.stopStreamingSkeleton();
  });
}

void PipelinePanel::applyLiveOut() {
  const std::optional<OscTarget> target = live_out_->wantedTarget();  // said at once when wrong
  if (!worker_) return;
  if (target)
    worker_->streamSkeleton(*target);
  else
    worker_->stopStreamingSkeleton();
}

}  // namespace lumistage
