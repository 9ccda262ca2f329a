#pragma once

#include <vector>

#include "core/render/orbit_view.h"

namespace lumistage {

struct CameraKey {
  double time_s = 0;
  ViewPose pose;
};

// A virtual camera's path on a timeline: keyframes of the view, played back smoothly. Between
// keys the centre follows a Catmull-Rom spline through the keys, the orientation turns along the
// shortest arc (quaternion slerp) and the field of view changes linearly. Before the first key
// and after the last the path holds still.
class CameraPath {
 public:
  // Adds a key at `time_s`, replacing a key within 1 ms of it. Keys stay sorted by time.
  void setKey(double time_s, const ViewPose& pose);
  // Removes the key nearest `time_s` within `tolerance_s`; false when there is none.
  bool removeKey(double time_s, double tolerance_s = 0.05);
  void clear() { keys_.clear(); }
  const std::vector<CameraKey>& keys() const { return keys_; }
  bool empty() const { return keys_.empty(); }
  double duration() const { return keys_.empty() ? 0 : keys_.back().time_s; }
  // The pose at `time_s`; the default pose when there are no keys.
  ViewPose at(double time_s) const;

 private:
  std::vector<CameraKey> keys_;
};

}  // namespace lumistage
