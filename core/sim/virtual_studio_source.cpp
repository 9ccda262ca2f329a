#include "core/sim/virtual_studio_source.h"

#include <cmath>
#include <thread>

namespace lumistage {

VirtualStudioSource::VirtualStudioSource(StudioConfig config, int loop_frames, bool paced)
    : studio_(std::move(config), loop_frames),
      loop_frames_(std::max(1, loop_frames)),
      paced_(paced),
      stats_(studio_.rig().cameraCount()) {
  for (CameraStats& s : stats_) s.temperature_c = std::nan("");
}

VirtualStudioSource::~VirtualStudioSource() = default;

bool VirtualStudioSource::next(CameraFrame& frame, std::chrono::milliseconds timeout) {
  const int cameras = studio_.rig().cameraCount();
  if (index_ < 0 || next_camera_ == cameras) {
    const int64_t following = index_ + 1;
    if (index_ < 0) start_ = std::chrono::steady_clock::now();
    if (paced_) {
      // Not before the set is due; a renderer slower than the frame rate simply runs late.
      const auto due =
          start_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                       std::chrono::duration<double>(following / studio_.config().fps));
      const auto now = std::chrono::steady_clock::now();
      if (due - now > timeout) {
        std::this_thread::sleep_for(timeout);
        return false;
      }
      if (due > now) std::this_thread::sleep_until(due);
    }
    studio_.renderFrame(static_cast<int>(following % loop_frames_), frame_);
    index_ = following;
    next_camera_ = 0;
  }
  const int c = next_camera_++;
  const Camera& camera = studio_.rig().camera(c);
  frame.camera = c;
  frame.frame_id = index_;
  frame.timestamp_ns = static_cast<int64_t>(std::llround(index_ * 1e9 / studio_.config().fps));
  rgbaToImage(frame_.images[c].data(), camera.width(), camera.height(),
              studio_.config().pixel_format, frame.image);
  CameraStats& s = stats_[c];
  ++s.frames;
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  s.frame_rate_hz = elapsed > 0 ? s.frames / elapsed : 0;
  return true;
}

CameraStats VirtualStudioSource::stats(int camera) const {
  return stats_.at(camera);
}

}  // namespace lumistage
