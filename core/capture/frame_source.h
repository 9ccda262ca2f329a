#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "core/capture/image.h"
#include "core/geometry/rig.h"

namespace lumistage {

// One image from one camera.
struct CameraFrame {
  int camera = -1;           // index into the source's rig
  int64_t frame_id = -1;     // the camera's frame counter (GigE Vision block id) or the session's
  int64_t timestamp_ns = 0;  // the camera's timestamp (or the recording's), nanoseconds
  Image image;
  // The actor's mask from another tool, when the source has one (FrameSource::hasMasks): one byte
  // a pixel of the image's size, non-zero on the actor; empty otherwise. Reused as the image is.
  std::vector<uint8_t> mask;
};

// Counters of one camera of a source, for camera health.
struct CameraStats {
  int64_t frames = 0;        // delivered
  int64_t dropped = 0;       // lost (incomplete buffers, gaps in frame ids, full pool)
  int64_t resends = 0;       // GigE Vision packet resends requested
  double frame_rate_hz = 0;  // measured over the last second or so
  double temperature_c = 0;  // NaN where the camera has no sensor
  std::string last_error;    // empty when none
};

// Where frames come from: Aravis cameras, recorded sessions, the virtual studio. Every camera of
// the source's rig delivers frames; next() hands them out as they arrive, any camera's.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual const Rig& rig() const = 0;
  // The next frame of any camera, waiting at most `timeout`. False on timeout or at the end of a
  // recording (see finished()). `frame`'s image buffer is reused: no allocation once warmed up.
  virtual bool next(CameraFrame& frame, std::chrono::milliseconds timeout) = 0;
  virtual bool finished() const { return false; }
  // Why it finished before its end (every frame left failed to decode, say), in words; empty when
  // it did not.
  virtual std::string failure() const { return {}; }
  virtual CameraStats stats(int camera) const = 0;
  // Whether every frame of the camera carries the actor's mask (CameraFrame::mask), which then
  // stands for the key: a recording without a green screen, segmented by another tool.
  virtual bool hasMasks(int /*camera*/) const { return false; }
  // Frames of the empty stage that the camera filmed before the take (a clean plate, which a stage
  // without a green screen is keyed on: BackgroundModel); none when it has none.
  virtual std::vector<Image> plateImages(int /*camera*/) { return {}; }
  // Whether its frame ids only count instants, so that another count that numbers the same
  // instants may replace it (cameras, live): true. A recording's ids, or the virtual studio's,
  // name their frames' content, which a shifted count would pair with other nodes' frames of other
  // instants: false.
  virtual bool idsCountInstants() const { return true; }
};

}  // namespace lumistage
