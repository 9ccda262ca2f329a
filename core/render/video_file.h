#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

namespace lumistage {

// Video files through FFmpeg's libraries (libavformat, libavcodec, libswscale).
//
// H.264 in MP4: libx264 where this FFmpeg has it (Debian's does), constant quality (CRF 20, High
// profile), otherwise FFmpeg's own MPEG-4 Part 2 encoder with one warning saying why. Motion-JPEG
// in AVI: FFmpeg's MJPEG encoder, full-range 4:2:0 at quantiser 2.
enum class VideoCodec { kH264, kMjpeg };

// How hard libx264 works: kQuality (preset veryfast) for files made offline (`lumistage render`),
// kLive (preset ultrafast, larger files, a key frame a second) where frames come from the running
// pipeline and must not hold it up (the view recorder), kFeed (kLive tuned for latency: no
// look-ahead nor B-frames, a capped rate, pictures stamped by the clock) for a network feed
// (VideoFeed, core/live/video_feed.h; a file takes it as kLive). Motion-JPEG ignores it.
enum class VideoSpeed { kQuality, kLive, kFeed };

// The codec a file's name asks for: .mp4 (and .mov, .mkv) H.264, .avi Motion-JPEG. Throws Error
// naming the file for any other extension.
VideoCodec videoCodecFor(const std::filesystem::path& file);

// How the pixels given to VideoFileWriter::write lie in memory: 8 bits a channel.
enum class PixelOrder { kRgb, kRgba, kBgr, kBgra };
inline int bytesPerPixel(PixelOrder order) {
  return order == PixelOrder::kRgb || order == PixelOrder::kBgr ? 3 : 4;
}

// Writes one video stream at a constant frame rate: frame k is shown at k / fps seconds. Pixels go
// to 4:2:0 YUV, which needs even sizes: an odd width or height loses its last column or row (the
// video is width & ~1 by height & ~1; width() and height() say). The header is written when it
// opens, the trailer (MP4's index, AVI's) by close(). Once open, write() allocates nothing of its
// own (the YUV frame, the packet and the scaler are reused, VideoEncoder in video_encoder.h; the
// encoder allocates its packets). Not thread-safe.
class VideoFileWriter {
 public:
  // `codec`: default, the one the name asks for (videoCodecFor); given, the container is that
  // codec's (MP4 or AVI) whatever the name. Throws Error naming the file: a size below 2x2, a rate
  // outside (0, 1000], an unknown extension, a file that cannot be created (no folder, no rights),
  // no encoder.
  VideoFileWriter(const std::filesystem::path& file, int width, int height, double fps,
                  std::optional<VideoCodec> codec = std::nullopt,
                  VideoSpeed speed = VideoSpeed::kQuality);
  ~VideoFileWriter();  // closes if close() was not called; errors are then lost
  VideoFileWriter(const VideoFileWriter&) = delete;
  VideoFileWriter& operator=(const VideoFileWriter&) = delete;

  // One frame of the size given when opened, rows top first, `stride` bytes apart (0: packed).
  // Throws Error naming the file when it cannot be encoded or written (a full disk), or after
  // close().
  void write(const uint8_t* pixels, PixelOrder order, int stride = 0);
  // Drains the encoder, writes the trailer and closes the file. Throws Error naming the file when
  // any of it fails (a full disk); the file is then incomplete. A second call does nothing.
  void close();

  const std::filesystem::path& file() const;
  int width() const;  // of the video: even
  int height() const;
  double fps() const;
  int64_t framesWritten() const;
  VideoCodec codec() const;
  std::string encoderName() const;  // "libx264", "mpeg4" or "mjpeg"
  // Why the encoder is not the one asked for (no libx264 in this FFmpeg); empty when it is.
  const std::string& warning() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A video file as FFmpeg reads it: its first video stream's size, rate, codec and packets. Every
// packet is read (nothing decoded), so `frames` counts what is in the file, not what its header
// says.
struct VideoFileInfo {
  int width = 0, height = 0;
  double fps = 0;
  int64_t frames = 0;
  std::string codec;      // FFmpeg's name: "h264", "mpeg4", "mjpeg"
  std::string container;  // FFmpeg's name of the format: "mov,mp4,m4a,3gp,3g2,mj2", "avi"
};
// Throws Error naming the file when it cannot be opened or holds no video stream.
VideoFileInfo probeVideoFile(const std::filesystem::path& file);

// Copies the video stream of `in` into a new file `out` (its container chosen by its name, as
// videoCodecFor), packet for packet, nothing re-encoded: a fragmented MP4 left by a live recording
// that never closed becomes a plain MP4 with its index. Returns the frames copied. Throws Error
// naming the file: `in` unreadable or without video, `out` not writable.
int64_t copyVideoFile(const std::filesystem::path& in, const std::filesystem::path& out);

}  // namespace lumistage
