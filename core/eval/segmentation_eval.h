#pragma once

#include <vector>

#include "core/capture/session_reader.h"
#include "core/imaging/clean_plate.h"

namespace lumistage {

// The segmentation as the nodes run it: each camera's GreenScreenKeyer learns its screen from the
// session's first frame (or, where the session filmed the empty stage, its clean plate is learnt
// from that: sessionPlates), then keys every pixel of the scored frames, compared with the truth
// masks (truth/masks) of a virtual-studio session.
struct SegmentationScore {
  double missed_pct = 0;   // the actor's pixels keyed as screen, % of the actor's pixels
  double extra_pct = 0;    // screen pixels keyed as the actor, % of the actor's pixels
  double threshold = 0;    // the learned green-excess thresholds, mean over cameras
  int dimmest_screen = 0;  // the lowest of the cameras' darkest screen green excess
  int frames = 0;
};

// Scores `frames` (indices into the session). Throws Error naming the file when a truth mask
// cannot be read.
// `plates`: the cameras' clean plates (null: sessionPlates).
SegmentationScore evaluateSegmentation(const SessionReader& session, const std::vector<int>& frames,
                                       const CameraPlates* plates = nullptr);

}  // namespace lumistage
