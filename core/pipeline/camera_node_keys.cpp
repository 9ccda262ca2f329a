// How a camera node keys its cameras (CameraNode, camera_node.h): on a green screen learnt and
// checked from its sets, on a clean plate learnt from the empty stage (its source's plate frames,
// or its first sets), or from the frames' masks.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "core/imaging/clean_plate.h"
#include "core/pipeline/camera_node.h"

namespace lumistage {

void CameraNode::setUpKeys() {
  masked_.resize(cameras_.size());
  mask_keys_.resize(cameras_.size());
  plates_.resize(cameras_.size());
  for (size_t k = 0; k < cameras_.size(); ++k) {
    masked_[k] = source_->hasMasks(cameras_[k]);
    if (masked_[k]) {
      spdlog::info("node {}: camera {}: keyed from the session's masks (no green screen learnt)",
                   name_, rig_.camera(cameras_[k]).name());
    } else {
      plates_[k] = learnPlate(*source_, cameras_[k]);
    }
  }
  published_plates_ = std::make_shared<const CameraPlates>(plates_);
  plates_learning_.resize(cameras_.size());
  key_kinds_ = std::make_unique<std::atomic<const char*>[]>(cameras_.size());
  for (size_t k = 0; k < cameras_.size(); ++k) {
    if (options_.plate_frames > 0 && !masked_[k] && !plates_[k]) {
      const Camera& c = rig_.camera(cameras_[k]);
      plates_learning_[k] = std::make_unique<BackgroundModel>(c.width(), c.height());
      spdlog::info(
          "node {}: camera {}: learns its clean plate from the first {} sets (the empty "
          "stage)",
          name_, c.name(), options_.plate_frames);
    }
    key_kinds_[k] = masked_[k]            ? kKeyedFromMasks
                    : plates_[k]          ? kKeyedOnPlate
                    : plates_learning_[k] ? kLearningPlate
                                          : kKeyedOnGreen;
  }
}

std::shared_ptr<const BackgroundModel> CameraNode::learnPlate(FrameSource& source,
                                                              int camera) const {
  const Camera& c = rig_.camera(camera);
  int skipped = 0;
  std::shared_ptr<const BackgroundModel> plate = sourcePlate(source, camera, &skipped);
  if (skipped > 0) {
    spdlog::warn(
        "node {}: camera {}: {} frames of the empty stage not of its {}x{} pixels: left "
        "out of its plate",
        name_, c.name(), skipped, c.width(), c.height());
  }
  if (plate) {
    spdlog::info("node {}: camera {}: keyed on its clean plate ({} frames of the empty stage)",
                 name_, c.name(), plate->frames());
  }
  return plate;
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
  published_plates_ = std::make_shared<const CameraPlates>(plates_);
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
