#pragma once

// A receiver of a live video feed on a thread of its own, as ffplay or OBS's Media Source is one:
// FFmpeg's libavformat opens the URL (udp://127.0.0.1:PORT binds the port; srt:// with
// ?mode=listener listens, without it calls), probes the MPEG-TS, decodes its video and keeps the
// first pictures as RGB. It gives up at its deadline, so that a test never hangs on it.
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libswscale/swscale.h>
}

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace lumistage::testing {

struct DecodedPicture {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;                          // packed RGB24
  std::chrono::steady_clock::time_point decoded_at;  // when the decoder gave it
  const uint8_t* at(int x, int y) const { return &rgb[(size_t(y) * width + x) * 3]; }
};

// Whether a UDP socket of this machine is bound to `port` (/proc/net/udp and udp6): a receiver's
// listening, found without touching the port.
inline bool udpPortBound(int port) {
  for (const char* table : {"/proc/net/udp", "/proc/net/udp6"}) {
    FILE* f = std::fopen(table, "r");
    if (!f) continue;
    char line[512];
    while (std::fgets(line, sizeof line, f)) {
      unsigned slot = 0, local_port = 0;
      char address[64];
      if (std::sscanf(line, " %u: %63[0-9A-Fa-f]:%x", &slot, address, &local_port) == 3 &&
          int(local_port) == port) {
        std::fclose(f);
        return true;
      }
    }
    std::fclose(f);
  }
  return false;
}

// A UDP port on 127.0.0.1 nobody is bound to now (the system's choice, released).
inline int freeUdpPort() {
  const int s = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(s, reinterpret_cast<sockaddr*>(&address), sizeof address);
  socklen_t length = sizeof address;
  ::getsockname(s, reinterpret_cast<sockaddr*>(&address), &length);
  ::close(s);
  return ntohs(address.sin_port);
}

inline bool waitForUdpPort(int port, std::chrono::seconds within) {
  const auto end = std::chrono::steady_clock::now() + within;
  while (std::chrono::steady_clock::now() < end) {
    if (udpPortBound(port)) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

class FeedReceiver {
 public:
  // `low_delay`: as ffplay's `-fflags nobuffer -flags low_delay` (a receiver set for latency):
  // packets not held back for the analysis of the stream once it is open, and each picture out of
  // the decoder as soon as its packet is in.
  FeedReceiver(std::string url, size_t pictures,
               std::chrono::seconds give_up = std::chrono::seconds(90), bool low_delay = false)
      : url_(std::move(url)),
        wanted_(pictures),
        deadline_(std::chrono::steady_clock::now() + give_up),
        low_delay_(low_delay) {
    thread_ = std::thread([this] { run(); });
  }
  ~FeedReceiver() {
    stop_ = true;
    thread_.join();
  }

  // Until it has its pictures, or it gave up or failed (then fewer).
  std::vector<DecodedPicture> wait() {
    std::unique_lock lock(mutex_);
    done_.wait(lock, [&] { return finished_; });
    return pictures_;
  }
  bool finished() {
    std::lock_guard lock(mutex_);
    return finished_;
  }
  std::string error() {
    std::lock_guard lock(mutex_);
    return error_;
  }

 private:
  static int interrupted(void* opaque) {
    const FeedReceiver& r = *static_cast<const FeedReceiver*>(opaque);
    return r.stop_ || std::chrono::steady_clock::now() > r.deadline_;
  }

  void finish(const std::string& error) {
    std::lock_guard lock(mutex_);
    error_ = error;
    finished_ = true;
    done_.notify_all();
  }

  void run() {
    AVFormatContext* format = avformat_alloc_context();
    format->interrupt_callback = {&FeedReceiver::interrupted, this};
    AVCodecContext* decoder = nullptr;
    AVPacket* packet = av_packet_alloc();
    AVFrame* frame = av_frame_alloc();
    SwsContext* scaler = nullptr;
    std::string error;
    // A live stream's analysis done on its first pictures: a short feed (a run of 20 frames)
    // holds fewer than FFmpeg's default 20 to measure the rate on.
    AVDictionary* options = nullptr;
    av_dict_set(&options, "fpsprobesize", "2", 0);
    av_dict_set(&options, "analyzeduration", "500000", 0);
    if (low_delay_) av_dict_set(&options, "fflags", "nobuffer", 0);
    int code = avformat_open_input(&format, url_.c_str(), nullptr, &options);
    av_dict_free(&options);
    if (code < 0) {
      error = "cannot open " + url_ + ": " + std::to_string(code);
      format = nullptr;
    } else if ((code = avformat_find_stream_info(format, nullptr)) < 0) {
      error = "no stream information: " + std::to_string(code);
    }
    int index = -1;
    if (error.empty()) {
      index = av_find_best_stream(format, AVMEDIA_TYPE_VIDEO, -1, -1, nullptr, 0);
      if (index < 0) error = "no video stream";
    }
    if (error.empty()) {
      const AVCodecParameters* parameters = format->streams[index]->codecpar;
      const AVCodec* codec = avcodec_find_decoder(parameters->codec_id);
      decoder = avcodec_alloc_context3(codec);
      avcodec_parameters_to_context(decoder, parameters);
      if (low_delay_) decoder->flags |= AV_CODEC_FLAG_LOW_DELAY;
      if (!codec || avcodec_open2(decoder, codec, nullptr) < 0) error = "no decoder";
    }
    while (error.empty() && pictures_.size() < wanted_) {
      code = av_read_frame(format, packet);
      if (code < 0) {
        error = "read failed: " + std::to_string(code);
        break;
      }
      if (packet->stream_index == index) avcodec_send_packet(decoder, packet);
      av_packet_unref(packet);
      while (pictures_.size() < wanted_ && avcodec_receive_frame(decoder, frame) >= 0) {
        DecodedPicture picture;
        picture.decoded_at = std::chrono::steady_clock::now();
        picture.width = frame->width;
        picture.height = frame->height;
        picture.rgb.resize(size_t(frame->width) * frame->height * 3);
        scaler = sws_getCachedContext(scaler, frame->width, frame->height,
                                      AVPixelFormat(frame->format), frame->width, frame->height,
                                      AV_PIX_FMT_RGB24, SWS_POINT, nullptr, nullptr, nullptr);
        uint8_t* planes[1] = {picture.rgb.data()};
        const int strides[1] = {frame->width * 3};
        sws_scale(scaler, frame->data, frame->linesize, 0, frame->height, planes, strides);
        std::lock_guard lock(mutex_);
        pictures_.push_back(std::move(picture));
      }
    }
    sws_freeContext(scaler);
    av_frame_free(&frame);
    av_packet_free(&packet);
    avcodec_free_context(&decoder);
    if (format) avformat_close_input(&format);
    finish(error);
  }

  std::string url_;
  size_t wanted_;
  std::chrono::steady_clock::time_point deadline_;
  bool low_delay_ = false;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::condition_variable done_;
  bool finished_ = false;
  std::string error_;
  std::vector<DecodedPicture> pictures_;
  std::thread thread_;
};

}  // namespace lumistage::testing
