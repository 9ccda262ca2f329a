#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/capture/image.h"
#include "core/geometry/rig.h"

namespace lumistage {

// What virtual cameras show: for each camera of the rig, a loop of frames in one pixel format.
struct FrameLoop {
  double fps = 25.0;
  std::vector<std::vector<Image>> frames;  // [camera][frame], all of the camera's size

  int length() const { return frames.empty() ? 0 : static_cast<int>(frames[0].size()); }
};

// Pacing of virtual cameras. Frames are sent on ticks of the monotonic clock, every camera
// period, so every camera of a process running at one rate sends at the same instants, stamped
// with the same timestamp (tick x period) and GigE Vision frame id: a client groups them exactly.
// The loop's content advances in real time whatever the cameras' rate.
int64_t cameraTick(int64_t monotonic_ns, int64_t period_ns);
int64_t tickTimestampNs(int64_t tick, int64_t period_ns);
// The loop frame showing at a timestamp.
int loopFrameAt(int64_t timestamp_ns, double loop_fps, int loop_length);

// Serves a FrameLoop through Aravis's fake GigE Vision camera (the real GVCP/GVSP protocol), one
// camera per rig camera, each on its own IP address: by default camera i at 127.0.1.(i+1). Each
// address must belong to a network interface of this machine (Aravis binds the fake camera to an
// interface address): on loopback, add them once with `ip addr add 127.0.1.2/8 dev lo` (or run in
// a network namespace, as the tests do). Any GigE Vision client can open the cameras by address;
// broadcast discovery does not reach loopback.
class VirtualGigeCameras {
 public:
  // Throws Error naming the camera and the address that could not be served.
  VirtualGigeCameras(const Rig& rig, std::shared_ptr<const FrameLoop> loop, PixelFormat format,
                     const std::string& first_address = "127.0.1.1");
  ~VirtualGigeCameras();
  VirtualGigeCameras(const VirtualGigeCameras&) = delete;
  VirtualGigeCameras& operator=(const VirtualGigeCameras&) = delete;

  const std::vector<std::string>& addresses() const { return addresses_; }
  // The address of camera i when the first is `first_address` (the last octet counts up).
  static std::string addressOf(const std::string& first_address, int camera);

 private:
  struct Served;
  std::vector<std::unique_ptr<Served>> served_;
  std::vector<std::string> addresses_;
};

}  // namespace lumistage
