#include "ui/live_feed_control.h"

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

LiveFeedControl::LiveFeedControl(QWidget* parent)
    : QWidget(parent),
      box_(new QCheckBox(tr("Live view to"), this)),
      url_(new QLineEdit(this)),
      status_(new QLabel(this)) {
  box_->setObjectName("live_feed");
  box_->setToolTip(
      tr("Sends the director's view live as H.264 in MPEG-TS, as lumistage run --feed: OBS (a "
         "Media Source with the URL), vMix or ffplay take it"));
  url_->setObjectName("live_feed_url");
  url_->setToolTip(
      tr("udp://HOST:PORT, srt://HOST:PORT (calling a receiver that listens) or "
         "srt://:PORT?mode=listener (the receiver calls the studio)"));
  url_->setText(QSettings("Lumistage", "Studio")
                    .value("pipeline/feed", QString("srt://:9000?mode=listener"))
                    .toString());
  url_->setMinimumWidth(190);
  url_->setMaximumWidth(230);
  status_->setObjectName("live_feed_status");
  auto* layout = new QHBoxLayout(this);
  layout->setContentsMargins(0, 0, 0, 0);
  layout->addWidget(box_);
  layout->addWidget(url_);
  layout->addWidget(status_);
  connect(box_, &QCheckBox::toggled, this, [this] {
    status_->clear();
    status_->setToolTip({});
    emit toggled();
  });
  // Another URL, typed while feeding: Enter moves the feed there.
  connect(url_, &QLineEdit::returnPressed, this, [this] {
    if (box_->isChecked()) emit toggled();
  });
}

std::optional<FeedTarget> LiveFeedControl::wantedTarget() {
  if (!box_->isChecked()) return std::nullopt;
  try {
    FeedTarget target = parseFeedUrl(url_->text().trimmed().toStdString());
    QSettings("Lumistage", "Studio").setValue("pipeline/feed", url_->text().trimmed());
    return target;
  } catch (const Error& e) {
    feedFailed(QString::fromStdString(e.what()), tr("expected udp:// or srt://"));
    return std::nullopt;
  }
}

void LiveFeedControl::showFeed(const QString& url, int64_t sent, int64_t dropped,
                               const QString& error) {
  if (url.isEmpty()) {
    if (!status_->text().startsWith("<b")) status_->clear();  // a failure stays until a new try
    return;
  }
  if (!error.isEmpty()) {
    feedFailed(error, tr("stopped"));
    return;
  }
  status_->setText(tr("%1 sent, %2 dropped").arg(sent).arg(dropped));
  status_->setToolTip(tr("Frames of the view sent to %1, and dropped when the feed could not "
                         "take them (busy, or no receiver yet)")
                          .arg(url));
}

void LiveFeedControl::feedFailed(const QString& why, const QString& briefly) {
  {
    const QSignalBlocker quiet(box_);  // unchecked here: nothing to stop
    box_->setChecked(false);
  }
  const QString words = briefly.isEmpty() ? tr("not sent") : tr("not sent: %1").arg(briefly);
  status_->setText("<b style='color:#e33'>" + words.toHtmlEscaped() + "</b>");
  status_->setToolTip(why);
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
    emit message(tr("Feeding the view to %1 (H.264 in MPEG-TS)").arg(where));
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
