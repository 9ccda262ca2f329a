#include "core/capture/frame_grouper.h"

#include <algorithm>
#include <cstdlib>
#include <utility>

namespace lumistage {

FrameGrouper::FrameGrouper(int camera_count, FrameGrouperOptions options)
    : cameras_(std::max(camera_count, 0)), options_(options) {
  options_.max_pending = std::max(options_.max_pending, 1);
  options_.max_ready = std::max(options_.max_ready, 1);
  stats_.missed.assign(cameras_, 0);
}

int64_t FrameGrouper::keyOf(const CameraFrame& frame) const {
  return options_.key == FrameGrouperOptions::Key::kFrameId ? frame.frame_id : frame.timestamp_ns;
}

int64_t FrameGrouper::keyOf(const FrameSet& set) const {
  return options_.key == FrameGrouperOptions::Key::kFrameId ? set.frame_id : set.timestamp_ns;
}

FrameSet FrameGrouper::newSet() {
  FrameSet set;
  if (!spare_sets_.empty()) {
    set = std::move(spare_sets_.back());
    spare_sets_.pop_back();
  }
  set.frames.resize(cameras_);
  set.present.assign(cameras_, false);
  set.missing.clear();
  return set;
}

bool FrameGrouper::push(CameraFrame& frame) {
  new_batch_ = true;
  const int c = frame.camera;
  const int64_t key = keyOf(frame);
  const bool by_id = options_.key == FrameGrouperOptions::Key::kFrameId;
  // A frame for an instant already emitted comes too late: it is counted, never waited for.
  const int64_t window = by_id ? 0 : options_.tolerance_ns;
  if (c < 0 || c >= cameras_ || (emitted_any_ && key <= last_emitted_key_ + window)) {
    ++stats_.stale;
    return false;
  }
  auto it = pending_.begin();
  for (; it != pending_.end(); ++it) {
    if (by_id ? it->frame_id == key
              : std::llabs(key - it->timestamp_ns) <= options_.tolerance_ns && !it->present[c]) {
      break;
    }
  }
  if (it != pending_.end() && it->present[c]) {  // the same camera twice for one id
    ++stats_.stale;
    return false;
  }
  if (it == pending_.end()) {
    FrameSet set = newSet();
    set.frame_id = frame.frame_id;
    set.timestamp_ns = frame.timestamp_ns;
    it = std::find_if(pending_.begin(), pending_.end(),
                      [&](const FrameSet& s) { return keyOf(s) > key; });
    it = pending_.insert(it, std::move(set));
  }
  // Swapped: the caller's frame gets back the slot's recycled buffer.
  std::swap(it->frames[c], frame);
  it->present[c] = true;
  if (std::all_of(it->present.begin(), it->present.end(), [](bool p) { return p; }))
    emitUpTo(size_t(it - pending_.begin()) + 1);
  while (pending_.size() > size_t(options_.max_pending)) emitUpTo(1);
  return true;
}

void FrameGrouper::emitUpTo(size_t count) {
  for (size_t i = 0; i < count && !pending_.empty(); ++i) {
    if (new_batch_) late_.clear();
    new_batch_ = false;
    FrameSet& set = pending_.front();
    set.missing.clear();
    if (options_.key == FrameGrouperOptions::Key::kFrameId) {
      // Each camera stamps its frames by its own clock (a GigE camera's ticks since power-up):
      // the set takes one camera's, the first present, not whichever arrived first.
      const auto first = std::find(set.present.begin(), set.present.end(), true);
      if (first != set.present.end())
        set.timestamp_ns = set.frames[first - set.present.begin()].timestamp_ns;
    }
    for (int c = 0; c < cameras_; ++c) {
      if (set.present[c]) continue;
      set.missing.push_back(c);
      ++stats_.missed[c];
    }
    ++(set.missing.empty() ? stats_.complete : stats_.incomplete);
    for (int c : set.missing) {
      if (std::find(late_.begin(), late_.end(), c) == late_.end()) late_.push_back(c);
    }
    emitted_any_ = true;
    last_emitted_key_ = keyOf(set);
    ready_.push_back(std::move(set));
    pending_.pop_front();
    while (ready_.size() > size_t(options_.max_ready)) {
      ++stats_.evicted;
      spare_sets_.push_back(std::move(ready_.front()));
      ready_.pop_front();
    }
  }
}

bool FrameGrouper::pop(FrameSet& set) {
  if (ready_.empty()) return false;
  const size_t spare_limit = size_t(options_.max_pending + options_.max_ready);
  if (set.frames.size() == size_t(cameras_) && spare_sets_.size() < spare_limit)
    spare_sets_.push_back(std::move(set));
  set = std::move(ready_.front());
  ready_.pop_front();
  return true;
}

void FrameGrouper::flush() {
  emitUpTo(pending_.size());
}

}  // namespace lumistage
