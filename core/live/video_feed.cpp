#include "core/live/video_feed.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
}

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <thread>
#include <vector>

#include "core/base/error.h"
#include "core/live/v4l2_output.h"
#include "core/render/video_encoder.h"

namespace lumistage {

namespace {

using Clock = std::chrono::steady_clock;

std::string lowercase(std::string text) {
  for (char& c : text) c = char(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

// An SRT caller's receiver has this long to answer (libsrt's own connection timeout is 3 s; this
// bounds the wait should it not report).
constexpr auto kCallTimeout = std::chrono::seconds(5);
// Sending a picture waits at most this long on the network (FFmpeg's rw_timeout, µs).
constexpr const char* kSendTimeoutUs = "1000000";

}  // namespace

bool ffmpegCanSend(const std::string& protocol) {
  void* state = nullptr;
  while (const char* name = avio_enum_protocols(&state, 1)) {
    if (protocol == name) return true;
  }
  return false;
}

std::string FeedTarget::carries() const {
  return protocol == Protocol::kV4l2 ? "uncompressed I420 to a video4linux2 device"
                                     : "H.264 in MPEG-TS";
}

FeedTarget parseFeedUrl(const std::string& url) {
  const std::string expected =
      "expected udp://HOST:PORT, srt://HOST:PORT (srt://:PORT?mode=listener to let the "
      "receiver call) or v4l2:///dev/videoN";
  auto fail = [&](const std::string& why) {
    return Error("feed " + quotedInput(url) + ": " + why + "; " + expected);
  };
  FeedTarget t;
  t.url = url;
  const size_t colon = url.find("://");
  if (colon == std::string::npos) throw fail("not a URL");
  const std::string scheme = lowercase(url.substr(0, colon));
  if (scheme == "udp") {
    t.protocol = FeedTarget::Protocol::kUdp;
  } else if (scheme == "srt") {
    t.protocol = FeedTarget::Protocol::kSrt;
  } else if (scheme == "v4l2") {
    t.protocol = FeedTarget::Protocol::kV4l2;
    t.device = url.substr(colon + 3);
    if (t.device.empty() || t.device.front() != '/')
      throw fail("a v4l2 feed names its device by its whole path (three slashes)");
    return t;
  } else {
    throw fail("a feed goes out over udp, srt or to a v4l2 device, not " + quotedInput(scheme));
  }
  const size_t at = colon + 3;
  const size_t query = url.find('?', at);
  const std::string address =
      url.substr(at, query == std::string::npos ? std::string::npos : query - at);
  if (address.find('/') != std::string::npos) throw fail("a feed's URL has no path");
  // HOST:PORT, [IPv6]:PORT
  const size_t port_colon = address.rfind(':');
  if (port_colon == std::string::npos ||
      (address.find(']') != std::string::npos && port_colon < address.find(']')))
    throw fail("no port");
  t.host = address.substr(0, port_colon);
  if (t.host.size() >= 2 && t.host.front() == '[' && t.host.back() == ']')
    t.host = t.host.substr(1, t.host.size() - 2);
  const std::string port = address.substr(port_colon + 1);
  if (port.empty() || port.size() > 5 ||
      !std::all_of(port.begin(), port.end(), [](char c) { return c >= '0' && c <= '9'; }) ||
      std::stoi(port) < 1 || std::stoi(port) > 65535)
    throw fail("the port is " + quotedInput(port) + ", not 1 to 65535");
  t.port = std::stoi(port);
  if (query != std::string::npos) {
    std::string rest = url.substr(query + 1);
    while (!rest.empty()) {
      const size_t amp = rest.find('&');
      const std::string pair = rest.substr(0, amp);
      rest = amp == std::string::npos ? "" : rest.substr(amp + 1);
      if (pair.rfind("mode=", 0) != 0) continue;
      const std::string mode = pair.substr(5);
      if (t.protocol != FeedTarget::Protocol::kSrt) throw fail("mode= is SRT's");
      if (mode == "listener") {
        t.listener = true;
      } else if (mode != "caller") {
        throw fail("an SRT feed's mode is caller or listener, not " + quotedInput(mode));
      }
    }
  }
  if (t.host.empty() && !t.listener) throw fail("no host");
  if (t.protocol == FeedTarget::Protocol::kSrt && !ffmpegCanSend("srt"))
    throw Error("feed " + quotedInput(url) +
                ": this FFmpeg's libavformat was built without SRT (libsrt); send over "
                "udp://HOST:PORT instead");
  return t;
}

struct VideoFeed::Impl {
  FeedTarget target;
  int width = 0, height = 0;
  double fps = 0;
  Clock::time_point start = Clock::now();

  // Three pictures: offer() copies into `offered` (its own), then swaps it with the slot,
  // `pending`, which the thread swaps with its `working`: the lock is held for the swaps alone.
  mutable std::mutex mutex;
  std::condition_variable wake;
  std::vector<uint8_t> offered, pending, working;
  int pending_width = 0, pending_height = 0, working_width = 0, working_height = 0;
  PixelOrder pending_order = PixelOrder::kRgba, working_order = PixelOrder::kRgba;
  Clock::time_point pending_at, working_at;
  bool has_pending = false;
  std::string error, encoder_name;  // under mutex

  std::atomic<bool> stop{false}, failed{false}, connected{false};
  std::atomic<int64_t> open_deadline_ns{0};  // while an SRT caller connects; 0: none
  std::atomic<int64_t> sent{0}, dropped{0}, send_ns{0};
  std::atomic<int> connections{0};
  std::thread thread;

  // FFmpeg asks between its waits on the network: stop, or a call unanswered for too long.
  static int interrupted(void* opaque) {
    const Impl& f = *static_cast<const Impl*>(opaque);
    if (f.stop) return 1;
    const int64_t deadline = f.open_deadline_ns;
    return deadline != 0 && Clock::now().time_since_epoch().count() > deadline;
  }
  void run();
  // One connection: opened, fed until stopped or it fails. Empty when stopped, else why it ended;
  // `opened` says whether it got as far as sending. session() branches to v4l2Session() for a
  // device.
  std::string session(bool& opened);
  std::string v4l2Session(bool& opened);
  // Waits for an offered picture and takes it into `working`; false when stopping.
  bool takePending();
  void opened(bool& opened, const std::string& encoder) {
    {
      std::lock_guard lock(mutex);
      encoder_name = encoder;
    }
    opened = true;
    connected = true;
    ++connections;
  }
  void fail(const std::string& why) {
    {
      std::lock_guard lock(mutex);
      error = "feed to " + target.url + " stopped: " + why;
    }
    failed = true;
    connected = false;
  }
};

VideoFeed::VideoFeed(const FeedTarget& target, int width, int height, double fps)
    : impl_(std::make_unique<Impl>()) {
  quietFfmpeg();
  if (width < 2 || height < 2)
    throw Error("feed to " + target.url + ": cannot send a video of " + std::to_string(width) +
                "x" + std::to_string(height) + " (at least 2x2)");
  if (!(fps > 0 && fps <= 1000))
    throw Error("feed to " + target.url + ": cannot send a video at " + std::to_string(fps) +
                " frames a second (expected 0 to 1000)");
  Impl& f = *impl_;
  f.target = target;
  f.width = width & ~1;
  f.height = height & ~1;
  f.fps = fps;
  f.offered.resize(size_t(width) * height * 4);
  f.pending.resize(f.offered.size());
  f.working.resize(f.offered.size());
  f.thread = std::thread([&f] { f.run(); });
}

VideoFeed::~VideoFeed() {
  close();
}

void VideoFeed::close() {
  Impl& f = *impl_;
  if (!f.thread.joinable()) return;
  {
    std::lock_guard lock(f.mutex);
    f.stop = true;
  }
  f.wake.notify_all();
  f.thread.join();
  f.connected = false;
}

bool VideoFeed::offer(int width, int height, std::span<const uint8_t> pixels, PixelOrder order) {
  Impl& f = *impl_;
  const size_t bytes =
      size_t(std::max(width, 0)) * size_t(std::max(height, 0)) * size_t(bytesPerPixel(order));
  if (f.stop || f.failed || width < 2 || height < 2 || pixels.size() < bytes) return false;
  if (f.offered.size() < bytes) f.offered.resize(bytes);  // a larger picture than any before
  std::memcpy(f.offered.data(), pixels.data(), bytes);
  {
    std::lock_guard lock(f.mutex);
    if (f.has_pending) ++f.dropped;  // the thread has not taken it: the newest goes instead
    std::swap(f.offered, f.pending);
    f.pending_width = width;
    f.pending_height = height;
    f.pending_order = order;
    f.pending_at = Clock::now();
    f.has_pending = true;
  }
  f.wake.notify_one();
  return true;
}

void VideoFeed::Impl::run() {
  for (;;) {
    bool opened = false;
    const std::string why = session(opened);
    connected = false;
    if (stop) return;
    // An SRT listener whose receiver left listens for the next; anything else ends the feed.
    if (!(target.listener && opened)) {
      fail(why);
      std::lock_guard lock(mutex);
      if (has_pending) ++dropped;
      has_pending = false;
      return;
    }
  }
}

bool VideoFeed::Impl::takePending() {
  std::unique_lock lock(mutex);
  wake.wait(lock, [&] { return has_pending || stop; });
  if (stop) return false;
  std::swap(pending, working);
  working_width = pending_width;
  working_height = pending_height;
  working_order = pending_order;
  working_at = pending_at;
  has_pending = false;
  return true;
}

std::string VideoFeed::Impl::v4l2Session(bool& was_opened) {
  V4l2Output output(width, height);
  if (const Status open = output.open(target.device); !open.ok()) return open.error();
  opened(was_opened, "raw");
  while (takePending()) {
    const auto began = Clock::now();
    bool taken = false;
    try {
      const Status written =
          output.write(working.data(), working_order, working_width, working_height, taken);
      if (!written.ok()) return written.error();
    } catch (const Error& e) {
      return e.what();
    }
    if (!taken) {
      ++dropped;  // the device had no room for it
      continue;
    }
    ++sent;
    send_ns += std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - began).count();
  }
  return {};
}

std::string VideoFeed::Impl::session(bool& was_opened) {
  if (target.protocol == FeedTarget::Protocol::kV4l2) return v4l2Session(was_opened);
  AVFormatContext* format = nullptr;
  struct Close {
    AVFormatContext** format;
    ~Close() {
      if (*format) {
        if ((*format)->pb) avio_closep(&(*format)->pb);
        avformat_free_context(*format);
      }
    }
  } closing{&format};
  int code = avformat_alloc_output_context2(&format, nullptr, "mpegts", target.url.c_str());
  if (code < 0) return "cannot make an MPEG-TS stream (" + ffmpegError(code) + ")";
  std::unique_ptr<VideoEncoder> encoder;
  try {
    encoder = std::make_unique<VideoEncoder>("feed to " + target.url, VideoCodec::kH264,
                                             VideoSpeed::kFeed, width, height, fps, false);
  } catch (const Error& e) {
    return e.what();
  }
  AVStream* stream = avformat_new_stream(format, nullptr);
  if (!stream) return "out of memory for the video stream";
  code = avcodec_parameters_from_context(stream->codecpar, encoder->context());
  if (code < 0) return "cannot describe the video stream (" + ffmpegError(code) + ")";
  stream->time_base = encoder->context()->time_base;
  stream->avg_frame_rate = encoder->context()->framerate;
  AVDictionary* options = nullptr;
  av_dict_set(&options, "rw_timeout", kSendTimeoutUs, 0);
  if (target.protocol == FeedTarget::Protocol::kUdp) {
    av_dict_set(&options, "pkt_size", "1316", 0);  // the URL's own ?pkt_size= wins
  }
  const AVIOInterruptCB interrupt{&Impl::interrupted, this};
  if (target.protocol == FeedTarget::Protocol::kSrt && !target.listener)
    open_deadline_ns = (Clock::now() + kCallTimeout).time_since_epoch().count();
  code = avio_open2(&format->pb, target.url.c_str(), AVIO_FLAG_WRITE, &interrupt, &options);
  open_deadline_ns = 0;
  av_dict_free(&options);
  if (stop) return {};
  if (code < 0) {
    if (code == AVERROR_EXIT)
      return "no receiver answered within " + std::to_string(kCallTimeout.count()) + " s";
    if (target.protocol == FeedTarget::Protocol::kSrt && !target.listener)
      return "no receiver answered (" + ffmpegError(code) + ")";
    return "cannot open the connection (" + ffmpegError(code) + ")";
  }
  format->flags |= AVFMT_FLAG_FLUSH_PACKETS;  // each picture to the network when muxed
  // Each video packet's PES header gives its length (where it fits: under 64 KB): a receiver's
  // demultiplexer then hands the picture on when its last byte is in, instead of when the next
  // picture begins. A receiver on this PC: 70 -> 37 ms from offer() to the picture decoded, the
  // rest its H.264 parser's wait for the next picture (live_bench's videoFeedLatency).
  AVDictionary* muxing = nullptr;
  av_dict_set(&muxing, "omit_video_pes_length", "0", 0);
  code = avformat_write_header(format, &muxing);
  av_dict_free(&muxing);
  if (code < 0) return "cannot send the stream's header (" + ffmpegError(code) + ")";
  opened(was_opened, encoder->encoderName());
  int64_t last_pts = -1;
  std::string why;
  while (why.empty()) {
    if (!takePending()) break;
    const auto began = Clock::now();
    // Stamped by the clock when offered, in the encoder's 90 kHz: a receiver shows each picture
    // when it was made, however many were dropped between.
    const int64_t pts = std::max(
        last_pts + 1, int64_t(std::chrono::duration<double>(working_at - start).count() * 90000.0));
    last_pts = pts;
    try {
      encoder->send(working.data(), working_order, working_width, working_height, 0, pts);
      while (AVPacket* packet = encoder->receive()) {
        av_packet_rescale_ts(packet, encoder->context()->time_base, stream->time_base);
        packet->stream_index = stream->index;
        code = av_write_frame(format, packet);
        av_packet_unref(packet);
        if (code < 0 || format->pb->error < 0) {
          why = "cannot send (" + ffmpegError(code < 0 ? code : format->pb->error) +
                "): the receiver gone or the network down";
          break;
        }
      }
    } catch (const Error& e) {
      why = e.what();
    }
    if (!why.empty()) break;
    ++sent;
    send_ns += std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - began).count();
  }
  // The end of the stream; cut short when stopping (FFmpeg's writes are interrupted then).
  if (!stop) av_write_trailer(format);
  return stop ? std::string() : why;
}

const FeedTarget& VideoFeed::target() const {
  return impl_->target;
}
int VideoFeed::width() const {
  return impl_->width;
}
int VideoFeed::height() const {
  return impl_->height;
}
int64_t VideoFeed::framesSent() const {
  return impl_->sent;
}
int64_t VideoFeed::framesDropped() const {
  return impl_->dropped;
}
bool VideoFeed::connected() const {
  return impl_->connected;
}
int VideoFeed::connections() const {
  return impl_->connections;
}
Status VideoFeed::status() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->error.empty() ? Status() : Status::failure(impl_->error);
}
double VideoFeed::sendMs() const {
  const int64_t sent = impl_->sent;
  return sent > 0 ? double(impl_->send_ns.load()) / 1e6 / double(sent) : 0.0;
}
std::string VideoFeed::encoderName() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->encoder_name;
}

}  // namespace lumistage
