// A camera node's sets of frames (CameraNode, camera_node.h): the take's backlog of sets waiting
// for late frames and the pool of frames reused.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>

#include "core/pipeline/camera_node.h"

namespace lumistage {

void CameraNode::TakeBacklog::add(const std::shared_ptr<Set>& set, bool whole, bool late_only) {
  if (whole && waiting_.empty()) {
    offer(*set, {});
  } else if (whole || (late_only && takes_.wants(set->frame_id))) {
    waiting_.push_back({set, std::vector<CameraFrame>(whole ? 0 : cameras_)});
  }
}

bool CameraNode::TakeBacklog::catchLate(CameraFrame& frame, size_t k) {
  if (waiting_.empty() || frame.frame_id < waiting_.front().set->frame_id) return false;
  const auto it = std::find_if(waiting_.begin(), waiting_.end(),
                               [&](const Waiting& w) { return w.set->frame_id == frame.frame_id; });
  if (it == waiting_.end() || it->set->has(k)) return false;
  std::swap(it->late[k], frame);
  pool_.take(frame);
  return true;
}

void CameraNode::TakeBacklog::release(int64_t newest, bool all) {
  while (!waiting_.empty()) {
    Waiting& front = waiting_.front();
    if (front.complete()) {
      offer(*front.set, front.late);
    } else if (!all && front.set->frame_id >= newest - kLateFrames) {
      return;
    }
    pool_.give(front.late);
    waiting_.pop_front();
  }
}

bool CameraNode::TakeBacklog::Waiting::complete() const {
  for (size_t c = 0; c < late.size(); ++c)
    if (!set->has(c) && late[c].frame_id != set->frame_id) return false;
  return true;
}

void CameraNode::TakeBacklog::offer(const Set& set, const std::vector<CameraFrame>& late) {
  frames_.clear();
  for (size_t c = 0; c < cameras_; ++c) frames_.push_back(set.has(c) ? &set.frames[c] : &late[c]);
  takes_.offer(set.frame_id, frames_);
}

void CameraNode::FramePool::give(std::vector<CameraFrame>& frames) {
  std::lock_guard lock(mutex_);
  for (CameraFrame& frame : frames) {
    // Enough for the sets in flight and kept; beyond that, buffers are freed.
    if (frame.image.pixels.empty() || spare_.size() >= 32) continue;
    spare_.push_back(std::move(frame));
  }
}

void CameraNode::FramePool::take(CameraFrame& frame) {
  if (!frame.image.pixels.empty()) return;
  std::lock_guard lock(mutex_);
  if (spare_.empty()) return;
  frame = std::move(spare_.back());
  spare_.pop_back();
}

std::shared_ptr<CameraNode::Set> CameraNode::newSet() {
  return std::shared_ptr<Set>(new Set, [pool = frame_pool_](Set* set) {
    pool->give(set->frames);
    delete set;
  });
}

}  // namespace lumistage
