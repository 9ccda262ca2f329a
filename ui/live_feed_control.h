#pragma once

#include <QString>
#include <cstdint>
#include <optional>

#include "core/live/video_feed.h"
#include "ui/live_target_row.h"

namespace lumistage {

// The studio's live feed of the director's view (H.264 in MPEG-TS over UDP or SRT, as
// `lumistage run --feed`): a check box and the feed's URL, remembered between sessions (settings
// pipeline/feed). Checked while the pipeline runs, every blended view goes out; the pipeline panel
// asks its worker.
class LiveFeedControl : public LiveTargetRow {
  Q_OBJECT

 public:
  explicit LiveFeedControl(QWidget* parent = nullptr);
  // The feed's target when the box is checked and its text is a feed's URL; none otherwise (a
  // text that is not one unchecks the box and says why beside it).
  std::optional<FeedTarget> wantedTarget();
  // What the pipeline's snapshot says of the feed: its URL (empty: none), frames sent and dropped,
  // and why it stopped (empty while it runs).
  void showFeed(const QString& url, int64_t sent, int64_t dropped, const QString& error);
};

}  // namespace lumistage
