#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/base/status.h"
#include "core/capture/frame_source.h"

namespace lumistage {

// A GigE Vision or USB3 Vision camera found on the network or the bus.
struct AravisDeviceInfo {
  std::string id;  // Aravis device id, e.g. "Basler-21234567"
  std::string vendor, model, serial;
  std::string address;   // IP address for GigE Vision, empty for USB3
  std::string protocol;  // "GigEVision", "USB3Vision", "Fake"
};

// The most a socket's receive buffer may hold (net.core.rmem_max), in bytes; -1 when unknown.
int64_t receiveBufferLimit();
// What to do when that limit cannot hold two of a GigE Vision camera's images of `image_bytes`
// (the one arriving while the node takes the one before): Aravis sizes each stream's buffer to
// an image, the kernel caps it at the limit, and the packets past it are lost whenever the node
// is a moment late (resends, dropped frames). Empty when it can, or when the limit is unknown.
std::string receiveBufferAdvice(int64_t limit_bytes, int64_t image_bytes);

// Cameras Aravis can see: GigE Vision by broadcast discovery (which does not reach loopback:
// open virtual cameras by address), USB3 Vision on the bus.
std::vector<AravisDeviceInfo> discoverAravisCameras();

// A camera's frame ids, counting on across the wrap of GigE Vision 1.x's 16-bit block ids
// (1..65535, then 1 again: 36 minutes at 30 frames a second), so that every frame after it is not
// taken for one older than the last (the node's grouper and the studio would drop them all). Ids
// above 65535 (GigE Vision 2, USB3 Vision: 64 bits) are passed on as they are. Cameras' ids stay
// comparable (the nodes group frames by id) when they start streaming between the same two wraps,
// as cameras started together on a trigger do.
class FrameIdUnwrapper {
 public:
  int64_t operator()(int64_t raw) {
    if (last_raw_ >= 0 && raw < last_raw_ && last_raw_ <= kLargest &&
        last_raw_ - raw > kLargest / 2)
      epoch_ += kLargest;
    last_raw_ = raw;
    return raw <= kLargest ? epoch_ + raw : raw;
  }

 private:
  static constexpr int64_t kLargest = 65535;
  int64_t last_raw_ = -1, epoch_ = 0;
};

// A camera's dropped frames: those it delivered broken (missing packets, a short image) and the
// ids that never arrived, each counted once (a broken frame's own id, which the buffer may not
// carry reliably, is not trusted: it is the gap at the next whole frame that it fills).
class DropCounter {
 public:
  int64_t broken() {  // returns the frames newly counted as dropped
    ++broken_since_whole_;
    return 1;
  }
  int64_t whole(int64_t frame_id) {
    int64_t gap = 0;
    if (last_ >= 0 && frame_id > last_ + 1)
      gap = std::max<int64_t>(0, frame_id - last_ - 1 - broken_since_whole_);
    last_ = frame_id;
    broken_since_whole_ = 0;
    return gap;
  }

 private:
  int64_t last_ = -1, broken_since_whole_ = 0;
};

enum class TriggerMode {
  kFreeRunning,  // the camera's own frame rate
  kSoftware,     // AravisSource::trigger() fires every camera: a fallback for synchronisation
  kHardware,     // an external trigger line (synchronised cameras); see trigger_line
};

struct AravisCameraConfig {
  std::string device;  // IP address, serial number or Aravis device id; empty: not opened here
  PixelFormat pixel_format = PixelFormat::kBayerRggb8;
  double frame_rate_hz = 25.0;                                    // free running only
  double exposure_us = std::numeric_limits<double>::quiet_NaN();  // NaN: leave as the camera has it
  double gain_db = std::numeric_limits<double>::quiet_NaN();
  TriggerMode trigger = TriggerMode::kFreeRunning;
  std::string trigger_line = "Line0";
  int buffer_count = 8;  // the stream's buffer pool
};

// Frames from Aravis cameras, one per camera of the rig (or those of them with a device: a
// camera node opens its own), each camera configured to the rig's image size. One receiving thread
// per camera copies completed buffers into a bounded queue (the oldest frame is dropped, and
// counted, when the consumer falls behind) and hands the buffer straight back to the camera's pool.
class AravisSource : public FrameSource {
 public:
  // Opens and configures every camera, then starts streaming. A camera that cannot be opened
  // (not found, image size or pixel format not supported...) is left out, its error in its
  // stats(), and tried again every kRetryOpen; one lost while streaming (unplugged, powered off:
  // its control channel unanswered, or a free-running camera silent for kLostAfter) is closed
  // and opened again the same way, its frame ids lined up with the other cameras'. Throws Error
  // naming the cameras (rig name and device) and what failed when none can be opened.
  AravisSource(Rig rig, std::vector<AravisCameraConfig> cameras);
  ~AravisSource() override;

  const Rig& rig() const override { return rig_; }
  bool next(CameraFrame& frame, std::chrono::milliseconds timeout) override;
  CameraStats stats(int camera) const override;
  // Fires every camera in software trigger mode.
  void trigger();

 private:
  struct Device;
  // A camera that cannot be opened, or is lost while streaming, is opened again this often.
  static constexpr std::chrono::seconds kRetryOpen{5};
  // A free-running camera that sends nothing for this long is taken for lost.
  static constexpr std::chrono::seconds kLostAfter{5};
  void receive(int camera);
  // Under mutex_, for a frame of camera d that arrived whole: its id on the node's count (a camera
  // opened again realigned onto the freshest camera's), and its measured id rate updated.
  int64_t placedFrameId(Device& d, int64_t frame_id, int64_t arrived_ns);
  // Under mutex_: the frame queued (the oldest dropped when the consumer fell behind, a spare
  // image reused), its camera's counts and frame rate updated.
  void queueFrame(Device& d, int camera, int64_t frame_id, int64_t timestamp_ns, const void* data,
                  size_t bytes, std::chrono::steady_clock::time_point now);
  void openCamera(Device& d);   // camera configured and its stream made, no buffers yet
  void startCamera(Device& d);  // buffers given, acquisition started
  void closeCamera(Device& d);
  // One of the steps above; on an Error the camera is closed, the error (returned) in its stats.
  Status tryStep(Device& d, void (AravisSource::*step)(Device&));

  Rig rig_;
  std::vector<std::unique_ptr<Device>> devices_;
  std::atomic<bool> running_{true};
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<CameraFrame> queue_;  // delivered, waiting for next()
  std::vector<Image> spare_;       // images to reuse
  size_t capacity_;
};

}  // namespace lumistage
