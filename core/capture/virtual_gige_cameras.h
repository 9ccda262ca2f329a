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

// The frame of a loop that a virtual camera serves at a time. Frames are paced on the monotonic
// clock, so every camera of the process serves the same frame at the same instant, stamped with
// the same timestamp and GigE Vision frame id: a client can group them exactly.
int64_t loopTick(int64_t monotonic_ns, double fps);
int loopFrameOfTick(int64_t tick, int loop_length);
int64_t loopTimestampNs(int64_t tick, double fps);

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
