#include "core/live/v4l2_output.h"

extern "C" {
#include <libavutil/pixfmt.h>
}

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "core/base/error.h"

namespace lumistage {

namespace {

// ioctl, tried again when a signal interrupts it.
int control(int fd, unsigned long request, void* argument) {
  int result;
  do {
    result = ioctl(fd, request, argument);
  } while (result < 0 && errno == EINTR);
  return result;
}

}  // namespace

V4l2Output::V4l2Output(int width, int height)
    : width_(width & ~1),
      height_(height & ~1),
      picture_(size_t(std::max(width_, 0)) * size_t(std::max(height_, 0)) * 3 / 2) {}

V4l2Output::~V4l2Output() {
  close();
}

void V4l2Output::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

Status V4l2Output::open(const std::string& device) {
  close();
  name_ = "v4l2 output " + quotedInput(device);
  if (width_ < 2 || height_ < 2)
    return Status::failure(name_ + ": cannot send pictures of " + std::to_string(width_) + "x" +
                           std::to_string(height_));
  // Opened non-blocking before anything is known of it: a FIFO or a device that waits must not
  // hold the caller.
  const int fd = ::open(device.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0)
    return Status::failure(
        name_ + ": cannot open it (" + std::strerror(errno) + ")" +
        (errno == ENOENT ? "; load v4l2loopback (sudo modprobe v4l2loopback) to make one" : ""));
  struct Closer {
    int fd;
    bool keep = false;
    ~Closer() {
      if (!keep) ::close(fd);
    }
  } closer{fd};
  struct stat about {};
  if (fstat(fd, &about) != 0 || !S_ISCHR(about.st_mode))
    return Status::failure(name_ + ": not a device (expected /dev/videoN)");
  v4l2_capability capability{};
  if (control(fd, VIDIOC_QUERYCAP, &capability) != 0)
    return Status::failure(name_ +
                           ": not a V4L2 device; load v4l2loopback (sudo modprobe v4l2loopback) "
                           "and name the /dev/videoN it makes");
  const uint32_t caps = (capability.capabilities & V4L2_CAP_DEVICE_CAPS) != 0
                            ? capability.device_caps
                            : capability.capabilities;
  const std::string card(
      reinterpret_cast<const char*>(capability.card),
      strnlen(reinterpret_cast<const char*>(capability.card), sizeof capability.card));
  if ((caps & V4L2_CAP_VIDEO_OUTPUT) == 0)
    return Status::failure(name_ + " (" + quotedInput(card) +
                           "): a camera, not an output device; v4l2loopback makes one");
  if ((caps & V4L2_CAP_READWRITE) == 0)
    return Status::failure(name_ + " (" + quotedInput(card) +
                           "): takes no written pictures (no read/write I/O)");
  v4l2_format format{};
  format.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
  control(fd, VIDIOC_G_FMT, &format);  // what the driver holds; the fields set below replace it
  format.fmt.pix.width = uint32_t(width_);
  format.fmt.pix.height = uint32_t(height_);
  format.fmt.pix.pixelformat = V4L2_PIX_FMT_YUV420;
  format.fmt.pix.field = V4L2_FIELD_NONE;
  format.fmt.pix.bytesperline = uint32_t(width_);
  format.fmt.pix.sizeimage = uint32_t(picture_.size());
  format.fmt.pix.colorspace = V4L2_COLORSPACE_SMPTE170M;  // BT.601, as converted
  format.fmt.pix.quantization = V4L2_QUANTIZATION_LIM_RANGE;
  const std::string wanted = std::to_string(width_) + "x" + std::to_string(height_) + " I420";
  if (control(fd, VIDIOC_S_FMT, &format) != 0)
    return Status::failure(name_ + ": refused " + wanted + " (" + std::strerror(errno) +
                           "); another program may be writing to it, or it is fixed to another "
                           "format (v4l2loopback-ctl set-caps)");
  if (format.fmt.pix.width != uint32_t(width_) || format.fmt.pix.height != uint32_t(height_) ||
      format.fmt.pix.pixelformat != V4L2_PIX_FMT_YUV420)
    return Status::failure(name_ + ": asked for " + wanted + ", it holds " +
                           std::to_string(format.fmt.pix.width) + "x" +
                           std::to_string(format.fmt.pix.height) +
                           " in another format; give it this size (v4l2loopback-ctl set-caps) or "
                           "set the view to its size");
  closer.keep = true;
  fd_ = fd;
  return {};
}

std::span<const uint8_t> V4l2Output::convert(const uint8_t* pixels, PixelOrder order, int width,
                                             int height, int stride) {
  const size_t luma = size_t(width_) * height_;
  uint8_t* const planes[3] = {picture_.data(), picture_.data() + luma,
                              picture_.data() + luma * 5 / 4};
  const int strides[3] = {width_, width_ / 2, width_ / 2};
  converter_.convert(pixels, order, width, height, stride, width_, height_, AV_PIX_FMT_YUV420P,
                     false, planes, strides, name_);
  return picture_;
}

Status V4l2Output::write(const uint8_t* pixels, PixelOrder order, int width, int height,
                         bool& taken) {
  taken = false;
  if (fd_ < 0) return Status::failure(name_ + ": not open");
  const std::span<const uint8_t> picture = convert(pixels, order, width, height);
  ssize_t written;
  do {
    written = ::write(fd_, picture.data(), picture.size());
  } while (written < 0 && errno == EINTR);
  if (written < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK) return {};
    return Status::failure(name_ + ": cannot write (" + std::strerror(errno) + ")");
  }
  taken = true;
  return {};
}

}  // namespace lumistage
