#include "core/capture/virtual_gige_cameras.h"

#include <arpa/inet.h>
#include <arv.h>
#include <fmt/format.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <time.h>

#include <cmath>
#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/base/error.h"
#include "core/capture/aravis_pixel_format.h"

namespace lumistage {

int64_t cameraTick(int64_t monotonic_ns, int64_t period_ns) {
  return period_ns > 0 ? (monotonic_ns + period_ns / 2) / period_ns : 0;
}

int64_t tickTimestampNs(int64_t tick, int64_t period_ns) {
  return tick * period_ns;
}

int loopFrameAt(int64_t timestamp_ns, double loop_fps, int loop_length) {
  if (loop_length <= 0) return 0;
  // The small bias keeps a frame that starts exactly at a timestamp from rounding to the previous.
  const int64_t frame = static_cast<int64_t>(std::floor(timestamp_ns * 1e-9 * loop_fps + 1e-6));
  return static_cast<int>(((frame % loop_length) + loop_length) % loop_length);
}

namespace {

bool isLocalAddress(const std::string& address) {
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) != 0) return false;
  bool found = false;
  for (ifaddrs* a = list; a && !found; a = a->ifa_next) {
    if (!a->ifa_addr || a->ifa_addr->sa_family != AF_INET) continue;
    char text[INET_ADDRSTRLEN];
    inet_ntop(AF_INET, &reinterpret_cast<sockaddr_in*>(a->ifa_addr)->sin_addr, text, sizeof text);
    found = address == text;
  }
  freeifaddrs(list);
  return found;
}

int64_t monotonicNs() {
  timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return int64_t(t.tv_sec) * 1000000000 + t.tv_nsec;
}

// Writes `source` into `out` in `format`: exact where the source holds the information (RGB to
// anything, same to same), demosaiced from Bayer otherwise.
void convert(const Image& source, PixelFormat format, uint8_t* out) {
  const size_t n = size_t(source.width) * source.height;
  if (source.format == format) {
    std::memcpy(out, source.pixels.data(), source.pixels.size());
    return;
  }
  cv::Mat rgb;
  const cv::Mat plane(source.height, source.width, CV_8UC1,
                      const_cast<uint8_t*>(source.pixels.data()));
  if (source.format == PixelFormat::kRgb8) {
    rgb = cv::Mat(source.height, source.width, CV_8UC3, const_cast<uint8_t*>(source.pixels.data()));
  } else if (isBayer(source.format)) {
    // OpenCV names Bayer patterns by the second row's second and third pixels.
    const BayerLayout l = bayerLayout(source.format);
    const int code = l.red_y == 0 ? (l.red_x == 0 ? cv::COLOR_BayerBG2RGB : cv::COLOR_BayerGB2RGB)
                                  : (l.red_x == 0 ? cv::COLOR_BayerGR2RGB : cv::COLOR_BayerRG2RGB);
    cv::cvtColor(plane, rgb, code);
  } else {
    cv::cvtColor(plane, rgb, cv::COLOR_GRAY2RGB);
  }
  if (format == PixelFormat::kRgb8) {
    std::memcpy(out, rgb.data, n * 3);
    return;
  }
  cv::Mat rgba;
  cv::cvtColor(rgb, rgba, cv::COLOR_RGB2RGBA);
  Image converted;
  rgbaToImage(rgba.data, source.width, source.height, format, converted);
  std::memcpy(out, converted.pixels.data(), converted.pixels.size());
}

}  // namespace

struct VirtualGigeCameras::Served {
  ArvGvFakeCamera* gv = nullptr;
  ArvFakeCamera* fake = nullptr;
  std::shared_ptr<const FrameLoop> loop;
  int camera = 0;

  // Called by the fake camera's thread for every frame it sends.
  static void fill(ArvBuffer* buffer, void* data, guint32, guint32, ArvPixelFormat arv_format) {
    const Served& self = *static_cast<const Served*>(data);
    // The camera's own period (a client may have changed its frame rate).
    guint32 period_us = 0;
    arv_fake_camera_read_register(self.fake, ARV_FAKE_CAMERA_REGISTER_ACQUISITION_FRAME_PERIOD_US,
                                  &period_us);
    const int64_t period_ns = std::max<int64_t>(int64_t(period_us) * 1000, 1000);
    const int64_t tick = cameraTick(monotonicNs(), period_ns);
    const int64_t timestamp_ns = tickTimestampNs(tick, period_ns);
    const Image& image =
        self.loop
            ->frames[self.camera][loopFrameAt(timestamp_ns, self.loop->fps, self.loop->length())];
    const std::optional<PixelFormat> format = fromAravis(arv_format);
    // The buffer holds the camera's payload (the fake camera checked that); its received size is
    // not set until later, so arv_buffer_get_data reports 0 here: size it from the registers.
    size_t ignored = 0;
    auto* out = static_cast<uint8_t*>(const_cast<void*>(arv_buffer_get_data(buffer, &ignored)));
    if (!format || !out) return;  // a client set a format we cannot produce
    const size_t needed = size_t(image.width) * image.height * bytesPerPixel(*format);
    if (arv_fake_camera_get_payload(self.fake) < needed) return;  // a client shrank the image
    convert(image, *format, out);
    arv_buffer_set_timestamp(buffer, static_cast<guint64>(timestamp_ns));
    arv_buffer_set_frame_id(buffer,
                            static_cast<guint64>(tick % 65535 + 1));  // GigE Vision ids: 1..65535
  }
};

std::string VirtualGigeCameras::addressOf(const std::string& first_address, int camera) {
  in_addr a{};
  if (inet_pton(AF_INET, first_address.c_str(), &a) != 1) {
    throw Error("virtual cameras: '" + first_address + "' is not an IPv4 address");
  }
  a.s_addr = htonl(ntohl(a.s_addr) + static_cast<uint32_t>(camera));
  char text[INET_ADDRSTRLEN];
  inet_ntop(AF_INET, &a, text, sizeof text);
  return text;
}

VirtualGigeCameras::VirtualGigeCameras(const Rig& rig, std::shared_ptr<const FrameLoop> loop,
                                       PixelFormat format, const std::string& first_address) {
  if (!loop || loop->frames.size() != static_cast<size_t>(rig.cameraCount()) ||
      loop->length() == 0) {
    throw Error("virtual cameras: the frame loop must hold frames for every camera of the rig");
  }
  for (int c = 0; c < rig.cameraCount(); ++c) {
    const Camera& camera = rig.camera(c);
    for (const Image& image : loop->frames[c]) {
      if (image.width != camera.width() || image.height != camera.height()) {
        throw Error(fmt::format("virtual cameras: camera {} is {}x{} but its frames are {}x{}",
                                camera.name(), camera.width(), camera.height(), image.width,
                                image.height));
      }
    }
    const std::string address = addressOf(first_address, c);
    if (!isLocalAddress(address)) {
      throw Error(
          fmt::format("virtual camera {}: {} is not an address of this machine; GigE Vision needs "
                      "one address per "
                      "camera: add them once with `sudo ip addr add {}/8 dev lo` (one per camera), "
                      "or pick another "
                      "first address with --address",
                      camera.name(), address, address));
    }
    auto served = std::make_unique<Served>();
    served->loop = loop;
    served->camera = c;
    const std::string serial = "LUMI-" + camera.name();
    served->gv = arv_gv_fake_camera_new(address.c_str(), serial.c_str());
    if (!served->gv || !arv_gv_fake_camera_is_running(served->gv)) {
      g_clear_object(&served->gv);
      throw Error(fmt::format(
          "virtual camera {}: cannot serve GigE Vision on {} (is another camera or program "
          "using port 3956 there?)",
          camera.name(), address));
    }
    ArvFakeCamera* fake = arv_gv_fake_camera_get_fake_camera(served->gv);
    served->fake = fake;
    arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_WIDTH, camera.width());
    arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_HEIGHT, camera.height());
    arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_PIXEL_FORMAT, toAravis(format));
    arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_ACQUISITION_FRAME_PERIOD_US,
                                   static_cast<guint32>(std::llround(1e6 / loop->fps)));
    arv_fake_camera_set_fill_pattern(fake, &Served::fill, served.get());
    addresses_.push_back(address);
    served_.push_back(std::move(served));
  }
}

VirtualGigeCameras::~VirtualGigeCameras() {
  for (auto& s : served_) g_clear_object(&s->gv);
}

}  // namespace lumistage
