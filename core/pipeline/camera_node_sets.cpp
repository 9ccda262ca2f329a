// A camera node's sets of frames (CameraNode, camera_node.h): the take's backlog of sets waiting
// for late frames, the pool of frames reused, and the green screens checked and learnt from a set.
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

namespace {

// What is wrong with a camera's view of the screen whose darkest green excess is `excess` (empty:
// nothing), as the camera's health shows it.
std::string screenWarning(int excess) {
  if (excess == 0) return "sees no green screen to key";
  if (excess < GreenScreenKeyer::kDimScreenExcess) {
    return fmt::format(
        "green screen too dim to key cleanly (darkest green excess {} of 255 levels, {} "
        "wanted): light it brighter or more evenly",
        excess, GreenScreenKeyer::kDimScreenExcess);
  }
  return {};
}

}  // namespace

void CameraNode::checkScreens(const Set& set) {
  bool changed = false;
  for (size_t c = 0; c < cameras_.size(); ++c) {
    if (!keyedOnGreen(c)) continue;  // keyed from its masks or its plate: no screen to follow
    GreenScreenKeyer measured;
    measured.learnScreen(set.frames[c].image.view());
    const int was = keyers_[c].screenExcess(), excess = measured.screenExcess();
    const std::string& camera = rig_.camera(cameras_[c]).name();
    // Followed when two measurements in a row agree (one frame the actor stood close in, or a
    // flash, does not move the key), at once when the key never saw a screen (a lens cap off).
    GreenScreenKeyer& before = screen_measured_[c];
    const bool agreed = before.screenExcess() > 0 && !before.differs(measured);
    before = measured;
    const bool followed = (agreed || was == 0) && keyers_[c].follow(measured);
    changed = changed || followed;
    std::lock_guard lock(source_mutex_);
    // A screen warned of as too dim keeps its warning until it is a few levels brighter than
    // wanted, rather than the warning coming and going every second at the edge.
    const bool dim_before = screen_warnings_[c].find("too dim") != std::string::npos;
    std::string warning = screenWarning(excess);
    if (dim_before && warning.empty() &&
        excess < GreenScreenKeyer::kDimScreenExcess + GreenScreenKeyer::kFollowLevels)
      warning = screen_warnings_[c];
    // A warning is logged when it comes, not every time its figure moves.
    if (!warning.empty() && screen_warnings_[c].empty()) {
      spdlog::warn("node {}: camera {}: {}", name_, camera, warning);
    } else if (warning.empty() && followed) {
      spdlog::info(
          "node {}: camera {}: green screen learnt again (darkest green excess {} -> {}), "
          "key threshold {}",
          name_, camera, was, excess, keyers_[c].threshold());
    } else if (warning.empty() && !screen_warnings_[c].empty()) {
      spdlog::info("node {}: camera {}: green screen keys cleanly again (darkest green excess {})",
                   name_, camera, excess);
    }
    screen_warnings_[c] = std::move(warning);
  }
  if (changed) published_keyers_ = std::make_shared<const std::vector<GreenScreenKeyer>>(keyers_);
}

void CameraNode::learnPlates(Set& set) {
  bool learning = false;
  for (size_t c = 0; c < cameras_.size(); ++c) {
    if (!learningPlate(c)) continue;
    plates_learning_[c]->add(set.frames[c].image.view());
    learning = true;
  }
  if (!learning) return;
  set.empty_stage = true;
  if (++plate_sets_ < options_.plate_frames) return;
  for (size_t c = 0; c < cameras_.size(); ++c) {
    if (!learningPlate(c)) continue;
    plates_learning_[c]->learn();
    plates_[c] = std::move(plates_learning_[c]);
    key_kinds_[c] = kKeyedOnPlate;
    spdlog::info("node {}: camera {}: keyed on its clean plate ({} frames of the empty stage)",
                 name_, rig_.camera(cameras_[c]).name(), plates_[c]->frames());
  }
  published_plates_ =
      std::make_shared<const std::vector<std::shared_ptr<const BackgroundModel>>>(plates_);
}

void CameraNode::learnScreens(const Set& set) {
  bool clean = true;
  for (size_t c = 0; c < cameras_.size(); ++c) {
    if (!keyedOnGreen(c)) continue;  // keyed from its masks or its plate (said when made)
    keyers_[c].learnScreen(set.frames[c].image.view());
    clean = clean && keyers_[c].screenExcess() >= GreenScreenKeyer::kDimScreenExcess;
  }
  published_keyers_ = std::make_shared<const std::vector<GreenScreenKeyer>>(keyers_);
  ++screen_sets_learnt_;
  if (!clean && screen_sets_learnt_ < kScreenWarmupSets) return;  // settling, perhaps
  screen_sets_learnt_ = kScreenWarmupSets;  // learnt; checked every kScreenRetrySets from now on
  for (size_t c = 0; c < cameras_.size(); ++c) {
    if (!keyedOnGreen(c)) continue;
    const std::string& camera = rig_.camera(cameras_[c]).name();
    std::string warning = screenWarning(keyers_[c].screenExcess());
    if (warning.empty()) {
      spdlog::info("node {}: camera {}: green screen learnt, key threshold {}", name_, camera,
                   keyers_[c].threshold());
    } else {
      spdlog::warn("node {}: camera {}: {}", name_, camera, warning);
      // Shown in the studio's camera health while the camera reports no error of its own.
      std::lock_guard lock(source_mutex_);
      screen_warnings_[c] = std::move(warning);
    }
  }
}

}  // namespace lumistage
