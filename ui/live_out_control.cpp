#include "ui/live_out_control.h"

#include <QCheckBox>
#include <QHBoxLayout>
#include <QLabel>
#include <QLineEdit>
#include <QMutexLocker>
#include <QSettings>
#include <QSignalBlocker>
#include <exception>

#include "core/base/error.h"
#include "ui/pipeline_panel.h"

namespace lumistage {

LiveOutControl::LiveOutControl(QWidget* parent)
    : QWidget(parent),
      box_(new QCheckBox(tr("Live skeleton to"), this)),
      target_(new QLineEdit(this)),
      status_(new QLabel(this)) {
  box_->setObjectName("live_skeleton");
  box_->setToolTip(
      tr("Streams the tracked skeleton of every frame shown over OSC in the VMC protocol, as "
         "lumistage run --osc: VSeeFace, EVMC4U for Unity, VMC4UE for Unreal and the Blender "
         "add-ons receive it (their usual port is %1)")
          .arg(VmcSender::kDefaultPort));
  target_->setObjectName("live_skeleton_target");
  target_->setToolTip(tr("The receiver: HOST:PORT (IPv6 in brackets)"));
  target_->setText(QSettings("Lumistage", "Studio")
                       .value("pipeline/osc", QString("127.0.0.1:%1").arg(VmcSender::kDefaultPort))
                       .toString());
  target_->setMinimumWidth(150);
  target_->setMaximumWidth(170);
  status_->setObjectName("live_skeleton_status");
  auto* layout = new QHBoxLayout(this);
  layout->setContentsMargins(0, 0, 0, 0);
  layout->addWidget(box_);
  layout->addWidget(target_);
  layout->addWidget(status_);
  connect(box_, &QCheckBox::toggled, this, [this] {
    status_->clear();
    status_->setToolTip({});
    emit toggled();
  });
  // Another receiver, typed while streaming: Enter moves the stream there.
  connect(target_, &QLineEdit::returnPressed, this, [this] {
    if (box_->isChecked()) emit toggled();
  });
}

std::optional<OscTarget> LiveOutControl::wantedTarget() {
  if (!box_->isChecked()) return std::nullopt;
  try {
    OscTarget target = parseOscTarget(target_->text().trimmed().toStdString());
    QSettings("Lumistage", "Studio").setValue("pipeline/osc", target_->text().trimmed());
    return target;
  } catch (const Error& e) {
    streamFailed(QString::fromStdString(e.what()), tr("expected HOST:PORT"));
    return std::nullopt;
  }
}

void LiveOutControl::showStream(const QString& target, int64_t bundles) {
  if (target.isEmpty()) {
    if (!status_->text().startsWith("<b")) status_->clear();  // a failure stays until a new try
    return;
  }
  status_->setText(tr("%1 frames sent").arg(bundles));
  status_->setToolTip(tr("VMC bundles sent to %1, one a frame shown").arg(target));
}

void LiveOutControl::streamFailed(const QString& why, const QString& briefly) {
  {
    const QSignalBlocker quiet(box_);  // unchecked here: nothing to stop
    box_->setChecked(false);
  }
  // A few words on the row, the whole of it on hovering (the row has no room for a sentence).
  const QString words = briefly.isEmpty() ? tr("not sent") : tr("not sent: %1").arg(briefly);
  status_->setText("<b style='color:#e33'>" + words.toHtmlEscaped() + "</b>");
  status_->setToolTip(why);
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
