#pragma once

#include <cstdint>
#include <deque>
#include <vector>

#include "core/capture/frame_source.h"

namespace lumistage {

// The frames of one instant, one slot per camera of the rig.
struct FrameSet {
  int64_t frame_id = -1;  // by id: the set's id; by timestamp: its first frame's id
  // By id: the timestamp of its first present camera's frame (cameras' clocks may differ: one
  // camera's, always the same while it delivers); by timestamp: its first frame's.
  int64_t timestamp_ns = 0;
  std::vector<CameraFrame> frames;  // indexed by camera; meaningful where present[c]
  std::vector<bool> present;
  std::vector<int> missing;  // cameras without a frame in this set, ascending; empty: complete

  bool complete() const { return missing.empty(); }
};

struct FrameGrouperOptions {
  enum class Key { kFrameId, kTimestamp };
  Key key = Key::kFrameId;           // kTimestamp where cameras' frame ids are not comparable
  int64_t tolerance_ns = 2'000'000;  // kTimestamp: frames this close to a set's first are one
  int max_pending = 4;  // partial sets waited on; beyond, the oldest goes out incomplete
  int max_ready = 8;    // sets not yet popped; beyond, the oldest is evicted (and counted)
};

struct FrameGrouperStats {
  int64_t complete = 0;         // sets emitted complete
  int64_t incomplete = 0;       // sets emitted with cameras missing
  int64_t evicted = 0;          // sets dropped because nobody popped them
  int64_t stale = 0;            // frames that came after their set had gone out (or duplicates)
  std::vector<int64_t> missed;  // per camera: sets emitted without it
};

// Synchronisation: turns the frames of several cameras, in any interleaving, into sets of one
// frame per camera of one instant, in order. A set goes out as soon as it is complete; older
// sets still waiting then go out first, incomplete, naming their missing cameras, as does the
// oldest when more than max_pending wait. A camera that falls behind is therefore reported, never
// waited on forever, and memory stays bounded. Buffers circulate: push() hands back a spare
// frame to fill, pop() takes back the caller's previous set, so a warmed-up loop allocates
// nothing. Not thread-safe: one acquisition thread pushes and pops.
class FrameGrouper {
 public:
  FrameGrouper(int camera_count, FrameGrouperOptions options = {});

  // Takes `frame` (its camera in [0, camera_count)); `frame` gets back a spare buffer. False
  // when the frame was discarded: stale, a duplicate, or an unknown camera.
  bool push(CameraFrame& frame);
  // The next set in order, into `set` (whose previous frames are recycled). False when none.
  bool pop(FrameSet& set);
  // Emits every waiting set, incomplete ones included (end of stream).
  void flush();

  // Cameras missing from the sets emitted by the latest push() or flush() that emitted any:
  // the ones behind or losing frames. Empty once they catch up.
  const std::vector<int>& lateCameras() const { return late_; }
  const FrameGrouperStats& stats() const { return stats_; }
  int pendingCount() const { return static_cast<int>(pending_.size()); }
  int readyCount() const { return static_cast<int>(ready_.size()); }

 private:
  int64_t keyOf(const CameraFrame& frame) const;
  int64_t keyOf(const FrameSet& set) const;
  void emitUpTo(size_t count);  // the `count` oldest pending sets, in order
  FrameSet newSet();

  int cameras_;
  FrameGrouperOptions options_;
  std::deque<FrameSet> pending_;  // ordered by key, oldest first
  std::deque<FrameSet> ready_;
  std::vector<FrameSet> spare_sets_;
  bool emitted_any_ = false;
  int64_t last_emitted_key_ = 0;
  std::vector<int> late_;
  bool new_batch_ = false;  // the next emission starts a new late_
  FrameGrouperStats stats_;
};

}  // namespace lumistage
