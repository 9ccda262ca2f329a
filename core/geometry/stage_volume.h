#pragma once

#include <string>

#include "core/geometry/rig.h"

namespace lumistage {

// The stage box a rig's tracker carves: the rig file's `stage` where it gives one, else the box
// its cameras cover (coveredStage), else (cameras that share no view of the floor) the default
// StageBox, `guessed`. `how`: the box and where it came from, for the log.
struct StageChoice {
  StageBox box;
  bool guessed = false;
  std::string how;
};
StageChoice chooseStage(const Rig& rig);
inline StageBox stageVolume(const Rig& rig) {
  return chooseStage(rig).box;
}

// The box of floor the cameras see an actor on whole, from the floor to kCoveredTop_m: it bounds
// every column of the floor (its floor point and the point kCoveredTop_m above it) that lies
// inside the images of at least minViewsForStage() of the cameras, as the visual hull needs to be
// carved tight (searched on a grid of 5 cm, coarser for rings wider than 3.3 m; rounded out to
// 10 cm). It holds at least the default StageBox's floor and is at most kMaxCoveredSide_m a side
// (about its centre); std::nullopt when no column is seen so (cameras that share no view of the
// floor).
inline constexpr double kCoveredTop_m = 2.4;
inline constexpr double kMaxCoveredSide_m = 5.0;
std::optional<StageBox> coveredStage(const Rig& rig);
// Three quarters of the cameras (all of them up to 4): 9 of the reference rig's 12.
int minViewsForStage(int cameras);

// "3.0 x 3.0 m floor, 2.2 m high, centred on (0.0, 0.0)": for logs and `rig show`.
std::string describeStage(const StageBox& box);

}  // namespace lumistage
