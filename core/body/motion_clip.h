#pragma once

#include <string>
#include <vector>

#include "core/body/skeleton.h"

namespace lumistage {

// A motion: poses of one skeleton sampled at a fixed rate.
struct MotionClip {
  std::string name;
  double fps = 30.0;
  std::vector<Pose> frames;

  double durationSeconds() const { return frames.empty() ? 0.0 : (frames.size() - 1) / fps; }
  // The pose at a time, linearly interpolated between frames (root rotation by slerp), clamped to
  // the clip's ends.
  Pose sample(double time_s) const;
};

}  // namespace lumistage
