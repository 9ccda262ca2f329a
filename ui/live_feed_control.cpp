#include "ui/live_feed_control.h"

#include <QMutexLocker>
#include <exception>

#include "core/base/error.h"
#include "ui/pipeline_panel.h"

namespace lumistage {

namespace {

LiveTargetRowSpec viewFeedRow() {
  LiveTargetRowSpec spec;
  spec.label = QObject::tr("Live view to");
  spec.box_name = "live_feed";
  spec.box_tip = QObject::tr(
      "Sends the director's view live as H.264 in MPEG-TS, as lumistage run --feed: OBS (a "
      "Media Source with the URL), vMix or ffplay take it; or to a v4l2loopback device, which "
      "OBS and browsers see as a webcam");
  spec.target_name = "live_feed_url";
  spec.target_tip = QObject::tr(
      "udp://HOST:PORT, srt://HOST:PORT (calling a receiver that listens) or "
      "srt://:PORT?mode=listener (the receiver calls the studio), or v4l2:///dev/videoN (a "
      "v4l2loopback device)");
  spec.default_target = "srt://:9000?mode=listener";
  spec.target_min_width = 190;
  spec.target_max_width = 230;
  spec.setting = "pipeline/feed";
  spec.status_name = "live_feed_status";
  return spec;
}

}  // namespace

LiveFeedControl::LiveFeedControl(QWidget* parent) : LiveTargetRow(viewFeedRow(), parent) {}

std::optional<FeedTarget> LiveFeedControl::wantedTarget() {
  return LiveTargetRow::wantedTarget(parseFeedUrl, tr("expected udp://, srt:// or v4l2://"));
}

void LiveFeedControl::showFeed(const QString& url, int64_t sent, int64_t dropped,
                               const QString& error) {
  if (url.isEmpty()) {
    showStatus({});
    return;
  }
  if (!error.isEmpty()) {
    failed(error, tr("stopped"));
    return;
  }
  showStatus(tr("%1 sent, %2 dropped").arg(sent).arg(dropped),
             tr("Frames of the view sent to %1, and dropped when the feed could not take them "
                "(busy, or no receiver yet)")
                 .arg(url));
}

// The pipeline worker's side of it, here beside the control.
void PipelineWorker::feedView(const FeedTarget& target) {
  QMutexLocker lock(&mutex_);
  commands_.push_back([this, target](LocalPipelineRun& run) {
    const QString where = QString::fromStdString(target.url);
    try {
      run.feedView(target, [this](const std::string& error) {
        emit message(tr("Live view: %1").arg(QString::fromStdString(error)));
      });
    } catch (const std::exception& e) {
      emit viewFeedFailed(QString::fromStdString(e.what()));
      emit message(tr("Cannot feed the view: %1").arg(QString::fromStdString(e.what())));
      return;
    }
    emit message(
        tr("Feeding the view to %1 (%2)").arg(where, QString::fromStdString(target.carries())));
  });
}

void PipelineWorker::stopFeedingView() {
  QMutexLocker lock(&mutex_);
  commands_.push_back([this](LocalPipelineRun& run) {
    if (const std::unique_ptr<VideoFeed> feed = run.stopFeedingView()) {
      emit message(tr("Stopped the view's feed to %1 after %2 frames (%3 dropped)")
                       .arg(QString::fromStdString(feed->target().url))
                       .arg(feed->framesSent())
                       .arg(feed->framesDropped()));
    }
  });
}

void PipelinePanel::applyLiveFeed() {
  const std::optional<FeedTarget> target = live_feed_->wantedTarget();  // said at once when wrong
  if (!worker_) return;
  if (target)
    worker_->feedView(*target);
  else
    worker_->stopFeedingView();
}

}  // namespace lumistage
