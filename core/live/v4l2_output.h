#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/base/status.h"
#include "core/render/video_encoder.h"
#include "core/render/video_file.h"

namespace lumistage {

// A video4linux2 output device: a v4l2loopback device (`modprobe v4l2loopback`) that programs
// reading webcams (OBS's Video Capture Device, a browser, Zoom) see as a camera. Pictures are
// written uncompressed, YUV 4:2:0 (I420, BT.601 limited range, as webcams deliver), one write()
// each: nothing is encoded, so the device adds no latency of its own. The device is opened
// non-blocking: a picture it cannot take at once is dropped, never waited on.
class V4l2Output {
 public:
  // Pictures of width x height (even: an odd last column or row is left out). Opens nothing.
  V4l2Output(int width, int height);
  ~V4l2Output();
  V4l2Output(const V4l2Output&) = delete;
  V4l2Output& operator=(const V4l2Output&) = delete;

  // Opens `device` (/dev/videoN) for writing pictures of this size. Failed, naming the device: it
  // does not exist or cannot be opened (permissions), it is not a character device, it is not a
  // V4L2 output device (a capture-only webcam; the hint to load v4l2loopback), it does not take
  // write(), or it refused the size or I420.
  Status open(const std::string& device);
  bool isOpen() const { return fd_ >= 0; }
  void close();

  // One picture, rows top first, `order`'s bytes a pixel (`stride` bytes a row; 0: packed), as
  // I420 of this output's size (YuvConverter: BT.601 limited range; scaled when of another size).
  // Valid until the next call. Nothing is allocated once the first picture of a size and order has
  // been converted.
  std::span<const uint8_t> convert(const uint8_t* pixels, PixelOrder order, int width, int height,
                                   int stride = 0);
  // convert(), then written to the device. Ok with `taken` true when written, false when the
  // device could not take it now (dropped); failed when the device is gone or refuses pictures.
  Status write(const uint8_t* pixels, PixelOrder order, int width, int height, bool& taken);

  int width() const { return width_; }
  int height() const { return height_; }

 private:
  int width_, height_;
  int fd_ = -1;
  std::string name_ = "v4l2 output";  // begins the converter's messages
  YuvConverter converter_;
  std::vector<uint8_t> picture_;  // I420: Y, then U, then V
};

}  // namespace lumistage
