#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "core/base/status.h"
#include "core/render/video_file.h"

namespace lumistage {

// Where a live video feed goes: an FFmpeg URL of one of the two protocols a feed takes, or a
// video4linux2 output device.
//   udp://HOST:PORT              MPEG-TS in UDP datagrams of 1316 bytes (seven TS packets), sent
//                                whether anyone listens or not (multicast addresses too)
//   srt://HOST:PORT              SRT, calling a receiver that listens there (OBS, vMix, ffplay
//                                with ?mode=listener)
//   srt://[HOST]:PORT?mode=listener   SRT, listening for a receiver that calls (OBS's Media
//                                Source with srt://STUDIO:PORT); another may call when it leaves
//   v4l2:///dev/videoN           a v4l2loopback device: programs that read webcams (OBS's Video
//                                Capture Device) see the view as a camera (V4l2Output)
// Further ?key=value options go to FFmpeg's protocol as they are (latency=, passphrase=, ttl=).
struct FeedTarget {
  enum class Protocol { kUdp, kSrt, kV4l2 };
  Protocol protocol = Protocol::kUdp;
  std::string host;  // may be empty for an SRT listener (every interface)
  int port = 0;
  bool listener = false;  // SRT ?mode=listener
  std::string device;     // v4l2: the device's path
  std::string url;        // as given
  // What goes out, in words: "H.264 in MPEG-TS", "uncompressed I420 to a video4linux2 device".
  std::string carries() const;
};

// Parses `url` as above. Throws Error saying what is expected: another scheme (rtmp://, a file),
// no port or one outside 1-65535, no host (but for a listener), an SRT mode that is not caller or
// listener, SRT where this FFmpeg's libavformat was built without libsrt, a v4l2 URL without an
// absolute device path. Whether the device is one is found when the feed opens it.
FeedTarget parseFeedUrl(const std::string& url);

// Whether this FFmpeg's libavformat can send through `protocol` ("udp", "srt"): its output
// protocols (avio_enum_protocols).
bool ffmpegCanSend(const std::string& protocol);

// A live video feed of a stream of pictures (the director's view) to a FeedTarget, as OBS, vMix,
// ffplay or a vision mixer take it (a v4l2 device: uncompressed, through V4l2Output): H.264
// (libx264, VideoSpeed::kFeed: ultrafast, tuned for zero latency, a key frame a second, no
// B-frames, a capped rate) in MPEG-TS, each picture stamped by the clock when offered. A thread of
// its own opens the connection, encodes and sends, so that the caller never waits on the network:
// offer() copies the picture into a slot and returns; a picture the thread has not taken when the
// next comes is dropped (counted), the newest kept, so a feed that cannot keep up (a slow encoder,
// a stalled network, a receiver not yet connected) loses pictures and never delays the pipeline.
// Sending waits at most a second on the network; a failure (the connection refused or lost, a host
// that does not resolve, an SRT caller whose receiver does not answer within its 3 s) stops the
// feed, and error() says why in one line; an SRT listener whose receiver leaves listens again.
// Pictures are scaled to the feed's size when they are of another. Once open, nothing is allocated
// per picture but the encoder's packets.
class VideoFeed {
 public:
  // Starts the thread (the connection is made there). Throws Error: a size below 2x2, a rate
  // outside (0, 1000].
  VideoFeed(const FeedTarget& target, int width, int height, double fps);
  ~VideoFeed();  // close()
  VideoFeed(const VideoFeed&) = delete;
  VideoFeed& operator=(const VideoFeed&) = delete;

  // One picture, rows top first, packed, `order`'s bytes a pixel: copied, then handed to the
  // thread under a lock held for a swap. Never waits on the network. From one thread at a time.
  // False when the feed has stopped (error()) or been closed, or the picture is empty or smaller
  // than its size says.
  bool offer(int width, int height, std::span<const uint8_t> pixels,
             PixelOrder order = PixelOrder::kRgba);
  // Stops the thread (what it is sending is cut short: at most a few tenths of a second) and
  // closes the connection. A second call does nothing.
  void close();

  const FeedTarget& target() const;
  int width() const;  // of the video: even
  int height() const;
  int64_t framesSent() const;     // encoded and handed to the network
  int64_t framesDropped() const;  // offered while the thread was busy or connecting
  // Open and sending (UDP, v4l2: once open; SRT: a receiver has connected).
  bool connected() const;
  int connections() const;  // receivers connected so far (UDP: 1 once open)
  // Failed once the feed stopped on its own, saying why in one line naming the URL; ok while it
  // runs, and when close() stopped it.
  Status status() const;
  // The thread's time a sent picture took, encoding and sending, ms (mean; 0 before any).
  double sendMs() const;
  // Encoder's name ("libx264"; "mpeg4" where this FFmpeg has no libx264; "raw" to a v4l2
  // device), once open.
  std::string encoderName() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lumistage
