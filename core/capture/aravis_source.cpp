#include "core/capture/aravis_source.h"

#include <arpa/inet.h>
#include <arv.h>
#include <fmt/format.h>
#include <netinet/in.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>

#include "core/base/error.h"
#include "core/capture/aravis_pixel_format.h"

namespace lumistage {

namespace {

std::string takeError(GError*& error) {
  std::string message = error ? error->message : "unknown error";
  g_clear_error(&error);
  return message;
}

// A failed Aravis call as an Error naming the camera and the step.
void throwIfFailed(GError*& error, const std::string& camera, std::string_view step) {
  if (error) throw Error(fmt::format("camera {}: {}: {}", camera, step, takeError(error)));
}

const char* statusName(ArvBufferStatus status) {
  switch (status) {
    case ARV_BUFFER_STATUS_SUCCESS:
      return "success";
    case ARV_BUFFER_STATUS_CLEARED:
      return "cleared";
    case ARV_BUFFER_STATUS_TIMEOUT:
      return "timeout: packets missing";
    case ARV_BUFFER_STATUS_MISSING_PACKETS:
      return "missing packets";
    case ARV_BUFFER_STATUS_WRONG_PACKET_ID:
      return "wrong packet id";
    case ARV_BUFFER_STATUS_SIZE_MISMATCH:
      return "image larger than the buffer";
    case ARV_BUFFER_STATUS_FILLING:
      return "filling";
    case ARV_BUFFER_STATUS_ABORTED:
      return "aborted";
    default:
      return "unknown buffer status";
  }
}

}  // namespace

int64_t receiveBufferLimit() {
  std::ifstream in("/proc/sys/net/core/rmem_max");
  int64_t bytes = -1;
  if (!(in >> bytes)) return -1;
  return bytes;
}

std::string receiveBufferAdvice(int64_t limit_bytes, int64_t image_bytes) {
  if (limit_bytes < 0 || image_bytes <= 0 || limit_bytes >= 2 * image_bytes) return {};
  return fmt::format(
      "net.core.rmem_max is {} KB, less than two of the cameras' {} KB images: the kernel drops "
      "a GigE Vision stream's packets whenever this PC is a moment late (resends, dropped "
      "frames). Raise it: sudo sysctl -w net.core.rmem_max=33554432, and in "
      "/etc/sysctl.d/60-lumistage.conf to keep it (packaging/deploying-nodes.md, GigE Vision "
      "tuning)",
      limit_bytes / 1024, image_bytes / 1024);
}

std::vector<AravisDeviceInfo> discoverAravisCameras() {
  arv_update_device_list();
  std::vector<AravisDeviceInfo> out;
  const unsigned n = arv_get_n_devices();
  for (unsigned i = 0; i < n; ++i) {
    auto text = [](const char* s) { return std::string(s ? s : ""); };
    out.push_back({text(arv_get_device_id(i)), text(arv_get_device_vendor(i)),
                   text(arv_get_device_model(i)), text(arv_get_device_serial_nbr(i)),
                   text(arv_get_device_address(i)), text(arv_get_device_protocol(i))});
  }
  return out;
}

struct AravisSource::Device {
  std::string name;  // "cam01 (127.0.1.1)"
  AravisCameraConfig config;
  // Opened, replaced and closed by the camera's receiving thread (and the constructor before it
  // starts); read by trigger() and stats() under `objects`.
  ArvCamera* camera = nullptr;
  ArvStream* stream = nullptr;
  mutable std::mutex objects;
  int width = 0, height = 0;
  guint payload = 0;  // bytes of a frame, as the camera says
  bool gige = false;  // a GigE Vision camera (its stream over UDP)
  std::thread thread;
  std::atomic<bool> control_lost{false};  // Aravis lost the camera's control channel
  // Counters, guarded by AravisSource::mutex_.
  CameraStats stats;
  std::deque<std::chrono::steady_clock::time_point> recent;  // arrival times, for the frame rate
  DropCounter drops;
  FrameIdUnwrapper unwrap;
  // Added to the camera's frame ids: 0, or after a reconnection (the camera counts from 1 again)
  // what lines its ids up with the other cameras' (the newest id any of them delivered).
  int64_t id_offset = 0;
  bool realign = false;  // the next whole frame sets id_offset
  // Its newest whole frame's id (its offset added) and when it began to arrive (the host's clock,
  // ns), kept while it is lost; its first since it was opened; the rate its ids count at, measured
  // from the two (dropped frames counted), kept across a loss.
  int64_t last_id = -1, last_ns = 0, span_id = -1, span_ns = 0;
  double rate_hz = 0;
};

namespace {

void onControlLost(ArvDevice*, gpointer device) {
  static_cast<std::atomic<bool>*>(device)->store(true);
}

}  // namespace

namespace {

// Whether a GigE Vision device answers at `address` (dotted IPv4): a discovery command sent to it
// alone (GVCP on UDP 3956, which every device answers, whoever controls it), sent twice, 250 ms
// for an answer each. Not an IPv4 address (a serial, an id): true, for Aravis to find. Aravis
// opens devices one at a time, each that does not answer waiting out 2.5 s of retries: a rig of
// twelve cameras gone kept their reconnection attempts queued 30 s, and the process that wanted
// to stop waiting for them. Asked here first, a camera that is not there costs 0.5 s, and the
// cameras are asked at once (each camera's thread; the constructor's first attempts side by
// side).
bool answersGigEVision(const std::string& address) {
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(3956);
  if (inet_pton(AF_INET, address.c_str(), &to.sin_addr) != 1) return true;
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return true;  // let Aravis say what is wrong
  // GVCP header: key 0x42, flags (acknowledge), DISCOVERY_CMD, no payload, request id 1.
  const uint8_t discovery[8] = {0x42, 0x01, 0x00, 0x02, 0x00, 0x00, 0x00, 0x01};
  bool answered = false;
  for (int attempt = 0; attempt < 2 && !answered; ++attempt) {
    if (sendto(fd, discovery, sizeof discovery, 0, reinterpret_cast<const sockaddr*>(&to),
               sizeof to) < 0)
      break;
    pollfd in{fd, POLLIN, 0};
    uint8_t ack[512];
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(250);
    while (!answered) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          until - std::chrono::steady_clock::now());
      if (left.count() <= 0) break;
      const int ready = poll(&in, 1, int(left.count()));
      if (ready < 0 && errno == EINTR) continue;  // a signal (Ctrl-C's handler): wait on
      if (ready <= 0) break;
      const ssize_t n = recv(fd, ack, sizeof ack, 0);
      answered = n >= 8 && ack[2] == 0x00 && ack[3] == 0x03;  // DISCOVERY_ACK
    }
  }
  close(fd);
  return answered;
}

}  // namespace

void AravisSource::openCamera(Device& d) {
  if (!answersGigEVision(d.config.device)) {
    throw Error(fmt::format(
        "camera {}: cannot open: no GigE Vision device answers at {} (is the camera powered, on "
        "this subnet, its cable in?)",
        d.name, d.config.device));
  }
  GError* error = nullptr;
  auto check = [&](std::string_view step) { throwIfFailed(error, d.name, step); };
  ArvCamera* camera = arv_camera_new(d.config.device.c_str(), &error);
  if (!camera) {
    throw Error(
        fmt::format("camera {}: cannot open: {} (for GigE Vision, is the camera powered, on this "
                    "subnet, and not opened by another program?)",
                    d.name, takeError(error)));
  }
  {
    std::lock_guard lock(d.objects);
    d.camera = camera;
  }
  arv_camera_set_pixel_format(d.camera, toAravis(d.config.pixel_format), &error);
  check(fmt::format("pixel format {}", pixelFormatName(d.config.pixel_format)).c_str());
  arv_camera_set_region(d.camera, 0, 0, d.width, d.height, &error);
  check("image size");
  int x = 0, y = 0, w = 0, h = 0;
  arv_camera_get_region(d.camera, &x, &y, &w, &h, &error);
  check("image size");
  if (w != d.width || h != d.height) {
    throw Error(fmt::format("camera {}: delivers {}x{} images, the rig says {}x{}", d.name, w, h,
                            d.width, d.height));
  }
  if (d.config.trigger == TriggerMode::kFreeRunning) {
    arv_camera_clear_triggers(d.camera, &error);
    check("free running (no trigger)");
    arv_camera_set_frame_rate(d.camera, d.config.frame_rate_hz, &error);
    check(fmt::format("frame rate {} Hz", d.config.frame_rate_hz).c_str());
  } else {
    const std::string source =
        d.config.trigger == TriggerMode::kSoftware ? "Software" : d.config.trigger_line;
    arv_camera_set_trigger(d.camera, source.c_str(), &error);
    check(fmt::format("trigger on {}", source).c_str());
  }
  if (!std::isnan(d.config.exposure_us)) {
    arv_camera_set_exposure_time(d.camera, d.config.exposure_us, &error);
    check("exposure time");
  }
  if (!std::isnan(d.config.gain_db)) {
    arv_camera_set_gain(d.camera, d.config.gain_db, &error);
    check("gain");
  }
  d.gige = arv_camera_is_gv_device(d.camera);
  if (d.gige) {
    arv_camera_gv_auto_packet_size(d.camera, &error);
    g_clear_error(&error);  // not every camera negotiates; the default packet size works
  }
  ArvStream* stream = arv_camera_create_stream(d.camera, nullptr, nullptr, &error);
  if (!stream)
    throw Error(fmt::format("camera {}: cannot open its stream: {}", d.name, takeError(error)));
  {
    std::lock_guard lock(d.objects);
    d.stream = stream;
  }
  d.payload = arv_camera_get_payload(d.camera, &error);
  check("payload size");
  d.control_lost = false;
  g_signal_connect(arv_camera_get_device(d.camera), "control-lost", G_CALLBACK(onControlLost),
                   &d.control_lost);
}

void AravisSource::startCamera(Device& d) {
  for (int b = 0; b < d.config.buffer_count; ++b)
    arv_stream_push_buffer(d.stream, arv_buffer_new(d.payload, nullptr));
  GError* error = nullptr;
  arv_camera_start_acquisition(d.camera, &error);
  throwIfFailed(error, d.name, "start of acquisition");
}

Status AravisSource::tryStep(Device& d, void (AravisSource::*step)(Device&)) {
  try {
    (this->*step)(d);
    return {};
  } catch (const Error& e) {
    closeCamera(d);
    std::lock_guard lock(mutex_);
    d.stats.last_error = std::string(e.what()) + " (trying again)";
    return Status::failure(e.what());
  }
}

void AravisSource::closeCamera(Device& d) {
  if (d.camera) {
    g_signal_handlers_disconnect_by_data(arv_camera_get_device(d.camera), &d.control_lost);
    // A camera whose control channel went unanswered is not told to stop: every command to it
    // waits out Aravis's retries (seconds) for an answer that does not come.
    if (!d.control_lost) arv_camera_stop_acquisition(d.camera, nullptr);
  }
  std::lock_guard lock(d.objects);
  g_clear_object(&d.stream);
  g_clear_object(&d.camera);
}

AravisSource::AravisSource(Rig rig, std::vector<AravisCameraConfig> cameras)
    : rig_(std::move(rig)), capacity_(4 * std::max<size_t>(1, cameras.size())) {
  if (cameras.size() != static_cast<size_t>(rig_.cameraCount())) {
    throw Error(fmt::format("Aravis source: {} camera configurations for a rig of {} cameras",
                            cameras.size(), rig_.cameraCount()));
  }
  for (int c = 0; c < rig_.cameraCount(); ++c) {
    auto device = std::make_unique<Device>();
    device->config = cameras[c];
    device->name = rig_.camera(c).name() + " (" + cameras[c].device + ")";
    device->width = rig_.camera(c).width();
    device->height = rig_.camera(c).height();
    device->stats.temperature_c = std::numeric_limits<double>::quiet_NaN();
    devices_.push_back(std::move(device));
  }
  int asked = 0;
  for (const auto& d : devices_) asked += !d->config.device.empty();
  if (asked == 0) throw Error("Aravis source: no camera to open (every device is empty)");
  // A camera that cannot be opened does not keep the others from serving: it is tried again
  // every kRetryOpen by its thread, its error in its stats meanwhile. None opened: an error.
  std::vector<std::string> failures;
  const auto attempt = [&](Device& d, void (AravisSource::*step)(Device&)) {
    if (const Status done = tryStep(d, step); !done.ok()) failures.push_back(done.error());
  };
  {
    // Opened side by side: a camera that is not there costs its discovery's 0.5 s once, not once
    // per absent camera (Aravis itself opens those that answer one at a time).
    std::mutex failed;
    std::vector<std::thread> opening;
    for (auto& d : devices_) {
      if (d->config.device.empty()) continue;  // another node's
      opening.emplace_back([&, device = d.get()] {
        if (const Status opened = tryStep(*device, &AravisSource::openCamera); !opened.ok()) {
          std::lock_guard lock(failed);
          failures.push_back(opened.error());
        }
      });
    }
    for (std::thread& t : opening) t.join();
    std::sort(failures.begin(), failures.end());  // in the cameras' order, whoever finished first
  }
  // Every stream exists before any camera sends, and the streams get their buffers only then:
  // Aravis's packet-socket receiver binds to the interface before it filters by address, so a
  // stream opened while another camera streams takes in that camera's packets for an instant,
  // and with buffers waiting could assemble them into a whole frame under the wrong camera's
  // name: the virtual cameras' frame ids agree, so their packets fit (the likely cause of the
  // wrong frame Aravis.VirtualCamerasStreamTheSyntheticFramesBitExact once saw under load).
  for (auto& d : devices_) {
    if (d->stream) attempt(*d, &AravisSource::startCamera);
  }
  if (failures.size() == size_t(asked)) {
    running_ = false;
    std::string all;
    for (const std::string& f : failures) all += (all.empty() ? "" : "; ") + f;
    throw Error(all);
  }
  for (const std::string& f : failures)
    spdlog::warn("{}; the other cameras are served, this one is tried again every {} s", f,
                 std::chrono::duration_cast<std::chrono::seconds>(kRetryOpen).count());
  int64_t largest = 0;
  for (const auto& d : devices_) {
    if (d->gige) largest = std::max<int64_t>(largest, d->payload);
  }
  if (const std::string advice = receiveBufferAdvice(receiveBufferLimit(), largest);
      !advice.empty())
    spdlog::warn("{}", advice);
  for (int c = 0; c < rig_.cameraCount(); ++c) {
    if (!devices_[c]->config.device.empty())
      devices_[c]->thread = std::thread(&AravisSource::receive, this, c);
  }
}

AravisSource::~AravisSource() {
  // Each camera's thread closes its camera as it ends, all at once: a camera that went away
  // (unplugged, its server gone) takes seconds to close (its stop, its stream and its control
  // released each wait out the protocol's retries), and one after the other a rig of twelve kept
  // `lumistage stream` from exiting for 95 s.
  running_ = false;
  for (auto& d : devices_) {
    if (d->thread.joinable()) d->thread.join();
  }
  for (auto& d : devices_) closeCamera(*d);  // any a thread never ran for
}

int64_t AravisSource::placedFrameId(Device& d, int64_t frame_id, int64_t arrived_ns) {
  if (d.realign) {
    // Opened again, the camera counts from the start: its ids are put where the freshest
    // frame any camera of the node delivered (its own before it was lost among them) leads
    // on to this frame's arrival at the rate that camera's ids counted at, so that its
    // frames group with the others' again (within a frame: arrival times jitter, and a rate
    // measured over seconds is off by a fraction of a percent). Counted on from that frame's
    // id alone, a node whose cameras were all gone for seconds came back seconds behind the
    // other nodes' count, pairing other instants' images.
    d.realign = false;
    const Device* freshest = nullptr;
    for (const auto& other : devices_) {
      if (other->last_id >= 0 && (!freshest || other->last_ns > freshest->last_ns))
        freshest = other.get();
    }
    if (freshest) {
      const double rate = freshest->rate_hz > 0 ? freshest->rate_hz
                          : d.rate_hz > 0       ? d.rate_hz
                                                : d.config.frame_rate_hz;
      const int64_t since = std::llround((arrived_ns - freshest->last_ns) / 1e9 * rate);
      d.id_offset = freshest->last_id + std::max<int64_t>(0, since) - frame_id;
    } else {
      d.id_offset = 0;
    }
    d.span_id = -1;
  }
  frame_id += d.id_offset;
  if (d.span_id < 0) {
    d.span_id = frame_id, d.span_ns = arrived_ns;
  } else if (arrived_ns - d.span_ns > 1'000'000'000 && frame_id > d.span_id) {
    d.rate_hz = double(frame_id - d.span_id) / ((arrived_ns - d.span_ns) / 1e9);
  }
  return frame_id;
}

void AravisSource::queueFrame(Device& d, int camera, int64_t frame_id, int64_t timestamp_ns,
                              const void* data, size_t bytes,
                              std::chrono::steady_clock::time_point now) {
  d.stats.dropped += d.drops.whole(frame_id);  // a jump: frames that never arrived
  if (queue_.size() >= capacity_) {            // the consumer fell behind: drop the oldest frame
    ++devices_[queue_.front().camera]->stats.dropped;
    spare_.push_back(std::move(queue_.front().image));
    queue_.pop_front();
  }
  CameraFrame frame;
  if (!spare_.empty()) {
    frame.image = std::move(spare_.back());
    spare_.pop_back();
  }
  frame.camera = camera;
  frame.frame_id = frame_id;
  frame.timestamp_ns = timestamp_ns;
  frame.image.resize(d.config.pixel_format, d.width, d.height);
  std::memcpy(frame.image.pixels.data(), data, bytes);
  queue_.push_back(std::move(frame));
  ++d.stats.frames;
  d.recent.push_back(now);
  while (d.recent.size() > 1 && now - d.recent.front() > std::chrono::seconds(2))
    d.recent.pop_front();
  if (d.recent.size() > 1) {
    d.stats.frame_rate_hz =
        (d.recent.size() - 1) /
        std::chrono::duration<double>(d.recent.back() - d.recent.front()).count();
  }
}

void AravisSource::receive(int camera) {
  Device& d = *devices_[camera];
  const size_t bytes = size_t(d.width) * d.height * bytesPerPixel(d.config.pixel_format);
  auto last_temperature = std::chrono::steady_clock::now();
  auto next_open = std::chrono::steady_clock::now() + kRetryOpen;
  auto last_buffer = std::chrono::steady_clock::now();
  while (running_) {
    if (!d.stream) {
      const auto now = std::chrono::steady_clock::now();
      // Not open (it failed to, or was lost): tried again every kRetryOpen.
      if (now < next_open) {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        continue;
      }
      next_open = now + kRetryOpen;
      if (!tryStep(d, &AravisSource::openCamera).ok()) continue;
      // As at the start: the stream filters by address before it has buffers to fill.
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      if (!tryStep(d, &AravisSource::startCamera).ok()) continue;
      spdlog::info("camera {}: open, streaming", d.name);
      std::lock_guard lock(mutex_);
      d.stats.last_error.clear();
      d.unwrap = FrameIdUnwrapper();
      d.drops = DropCounter();
      d.realign = true;
      last_buffer = now;
      continue;
    }
    ArvBuffer* buffer = arv_stream_timeout_pop_buffer(d.stream, 100000);  // 100 ms, to notice stop
    const auto now = std::chrono::steady_clock::now();
    // Lost: Aravis lost its control channel (GigE Vision heartbeats unanswered: unplugged, powered
    // off), or a free-running camera sent nothing for kLostAfter. Closed, and opened again.
    const bool silent =
        d.config.trigger == TriggerMode::kFreeRunning && now - last_buffer > kLostAfter;
    if (!buffer && (d.control_lost || silent)) {
      spdlog::warn("camera {}: lost ({}): opening it again every {} s", d.name,
                   d.control_lost ? "no answer on its control channel" : "no frames",
                   std::chrono::duration_cast<std::chrono::seconds>(kRetryOpen).count());
      closeCamera(d);
      std::lock_guard lock(mutex_);
      d.stats.last_error = "lost: reconnecting";
      next_open = now;
      continue;
    }
    if (!buffer) continue;
    last_buffer = now;
    const ArvBufferStatus status = arv_buffer_get_status(buffer);
    size_t size = 0;
    const void* data = arv_buffer_get_data(buffer, &size);
    std::unique_lock lock(mutex_);
    if (status != ARV_BUFFER_STATUS_SUCCESS || size < bytes) {
      d.stats.dropped += d.drops.broken();
      d.stats.last_error = status != ARV_BUFFER_STATUS_SUCCESS
                               ? statusName(status)
                               : fmt::format("short image: {} bytes, expected {}", size, bytes);
    } else {
      int64_t frame_id = d.unwrap(static_cast<int64_t>(arv_buffer_get_frame_id(buffer)));
      // When the frame began to arrive, on the host's clock (Aravis's system timestamp).
      int64_t arrived_ns = int64_t(arv_buffer_get_system_timestamp(buffer));
      if (arrived_ns <= 0)
        arrived_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                         std::chrono::system_clock::now().time_since_epoch())
                         .count();
      frame_id = placedFrameId(d, frame_id, arrived_ns);
      d.last_id = frame_id, d.last_ns = arrived_ns;
      queueFrame(d, camera, frame_id, static_cast<int64_t>(arv_buffer_get_timestamp(buffer)), data,
                 bytes, now);
      ready_.notify_one();
    }
    lock.unlock();
    arv_stream_push_buffer(d.stream, buffer);
    // Temperature, where the camera reports it: a register read, once in a while.
    if (last_buffer - last_temperature > std::chrono::seconds(5)) {
      last_temperature = last_buffer;
      GError* error = nullptr;
      if (arv_camera_is_feature_available(d.camera, "DeviceTemperature", &error)) {
        const double t = arv_camera_get_float(d.camera, "DeviceTemperature", &error);
        if (!error) {
          std::lock_guard guard(mutex_);
          d.stats.temperature_c = t;
        }
      }
      g_clear_error(&error);
    }
  }
  closeCamera(d);  // here, beside the other cameras' threads (see ~AravisSource)
}

bool AravisSource::next(CameraFrame& frame, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  if (!ready_.wait_for(lock, timeout, [&] { return !queue_.empty(); })) return false;
  // Swap buffers: the caller's old image becomes a spare, so steady state allocates nothing.
  if (!frame.image.pixels.empty()) spare_.push_back(std::move(frame.image));
  frame = std::move(queue_.front());
  queue_.pop_front();
  return true;
}

CameraStats AravisSource::stats(int camera) const {
  const Device& d = *devices_.at(camera);
  CameraStats out;
  {
    std::lock_guard lock(mutex_);
    out = d.stats;
    // The rate is measured as frames arrive: a camera that stopped has none, not its last one.
    if (d.recent.empty() ||
        std::chrono::steady_clock::now() - d.recent.back() > std::chrono::seconds(2))
      out.frame_rate_hz = 0;
  }
  std::lock_guard lock(d.objects);  // the receiving thread may be opening it again
  if (d.stream && ARV_IS_GV_STREAM(d.stream)) {
    out.resends =
        static_cast<int64_t>(arv_stream_get_info_uint64_by_name(d.stream, "n_resend_requests"));
  }
  return out;
}

void AravisSource::trigger() {
  for (auto& d : devices_) {
    std::lock_guard objects(d->objects);
    if (!d->camera || d->config.trigger != TriggerMode::kSoftware) continue;
    GError* error = nullptr;
    arv_camera_software_trigger(d->camera, &error);
    if (error) {
      std::lock_guard lock(mutex_);
      d->stats.last_error = "software trigger: " + takeError(error);
    }
  }
}

}  // namespace lumistage
