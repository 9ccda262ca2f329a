#pragma once

#include <chrono>
#include <memory>
#include <vector>

#include "core/capture/frame_source.h"
#include "core/sim/virtual_studio.h"

namespace lumistage {

// The virtual studio as a live camera source: frame sets rendered on demand, frame by frame,
// paced at the studio's frame rate (or as fast as the renderer goes), looping over `loop_frames`.
// Owns its OpenGL context, so it must be created, used and destroyed on one thread.
class VirtualStudioSource : public FrameSource {
 public:
  VirtualStudioSource(StudioConfig config, int loop_frames, bool paced = true);
  ~VirtualStudioSource() override;

  const Rig& rig() const override { return studio_.rig(); }
  bool next(CameraFrame& frame, std::chrono::milliseconds timeout) override;
  CameraStats stats(int camera) const override;
  bool idsCountInstants() const override { return false; }  // an id names the pose it renders
  const VirtualStudio& studio() const { return studio_; }

 private:
  VirtualStudio studio_;
  int loop_frames_;
  bool paced_;
  StudioFrame frame_;
  int64_t index_ = -1;  // frame set being handed out
  int next_camera_ = 0;
  std::chrono::steady_clock::time_point start_;
  std::vector<CameraStats> stats_;
};

}  // namespace lumistage
