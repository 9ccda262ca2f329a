#pragma once

#include <Eigen/Core>

#include "core/body/motion_clip.h"
#include "core/body/skeleton.h"

namespace lumistage {

// Where and from when the motion plays on the stage. The default plays the clip as it is, from its
// first frame.
struct MotionPlacement {
  double start_s = 0;  // the session's first frame is the clip at this time
  // The mean of the root's floor position over the frames the session films moved to the stage
  // centre first (a BVH file's capture volume is not ours), then turned and moved as below.
  bool centre = false;
  double heading_deg = 0;  // turned about the vertical through the centre
  Eigen::Vector2d offset_m = Eigen::Vector2d::Zero();  // then moved on the floor
  bool operator==(const MotionPlacement&) const = default;
};

// Plays `clip` as `placement` says for `frame_count` frames at `fps` (the clip's own time from
// placement.start_s): every frame's root turned and moved on the floor, the joints' angles as they
// are. Throws Error when start_s lies past the clip's end.
void placeMotion(MotionClip& clip, const Skeleton& skeleton, const MotionPlacement& placement,
                 int frame_count, double fps);

}  // namespace lumistage
