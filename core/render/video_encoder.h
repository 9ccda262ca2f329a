#pragma once

#include <cstdint>
#include <string>

#include "core/render/video_file.h"

struct AVCodecContext;
struct AVFrame;
struct AVPacket;
struct SwsContext;

namespace lumistage {

// Packed RGB(A) pictures to 4:2:0 YUV planes (libswscale, BT.601's matrix): a picture of the
// target's size has its even part copied (an odd last column or row left out), one of another size
// is scaled (bilinear). The scaler is made once per source order and size: after the first picture
// of each, convert() allocates nothing. Shared by VideoEncoder and the v4l2 output.
class YuvConverter {
 public:
  YuvConverter() = default;
  ~YuvConverter();
  YuvConverter(const YuvConverter&) = delete;
  YuvConverter& operator=(const YuvConverter&) = delete;

  // `pixels`: rows top first, `stride` bytes apart (0: packed). Into `planes` (Y, U, V, with their
  // `strides`) of `width` x `height` (even) in `yuv_format` (an AVPixelFormat of 4:2:0 YUV),
  // `full_range` or limited. Throws Error, naming `name`, when libswscale cannot convert.
  void convert(const uint8_t* pixels, PixelOrder order, int source_width, int source_height,
               int stride, int width, int height, int yuv_format, bool full_range,
               uint8_t* const planes[], const int strides[], const std::string& name);

 private:
  SwsContext* scaler_ = nullptr;
  int input_ = -1;  // AVPixelFormat the scaler converts from, and the sizes
  int from_width_ = 0, from_height_ = 0, width_ = 0, height_ = 0;
};

// The encoding half of a video: RGB(A) pixels to 4:2:0 YUV (libswscale) to packets (libavcodec),
// shared by VideoFileWriter (a file) and VideoFeed (a network feed); each muxes the packets its
// own way. The codec and its settings are those video_file.h describes, per VideoCodec and
// VideoSpeed. Once open, send() allocates nothing of its own (the YUV frame, the packet and the
// scaler are reused; a source of another size makes a new scaler once). Not thread-safe.
class VideoEncoder {
 public:
  // `name` (the file or the URL) begins every message. `global_header`: the container wants the
  // codec's headers once, out of band (MP4), not with every key frame (AVI, MPEG-TS). Throws
  // Error: no encoder for the codec, the encoder refusing its settings.
  VideoEncoder(std::string name, VideoCodec codec, VideoSpeed speed, int width, int height,
               double fps, bool global_header);
  ~VideoEncoder();
  VideoEncoder(const VideoEncoder&) = delete;
  VideoEncoder& operator=(const VideoEncoder&) = delete;

  // One picture of `source_width` x `source_height` (rows top first, `stride` bytes apart, 0:
  // packed), shown at `pts` in timeBase() units; scaled to the video's size when it is another.
  // Then take its packets with receive(). Throws Error when it cannot be encoded.
  void send(const uint8_t* pixels, PixelOrder order, int source_width, int source_height,
            int stride, int64_t pts);
  // No more pictures: receive() then gives the packets the encoder still holds.
  void sendEnd();
  // The next packet (timestamps in timeBase()), valid until the next call; null when the encoder
  // wants another picture (or has ended). Throws Error when encoding failed.
  AVPacket* receive();

  AVCodecContext* context() const { return encoder_; }
  int width() const { return width_; }  // of the video: even
  int height() const { return height_; }
  std::string encoderName() const;  // "libx264", "mpeg4" or "mjpeg"
  // Why the encoder is not the one asked for (no libx264 in this FFmpeg); empty when it is.
  const std::string& warning() const { return warning_; }

 private:
  std::string name_;
  VideoCodec codec_;
  std::string warning_;
  int width_ = 0, height_ = 0;
  AVCodecContext* encoder_ = nullptr;
  AVFrame* frame_ = nullptr;
  AVPacket* packet_ = nullptr;
  YuvConverter converter_;
  void release();
};

// FFmpeg's text for an error code.
std::string ffmpegError(int code);
// Quiets FFmpeg's log, once: its banner, statistics and notes say nothing a user of Lumistage
// needs, and its errors come back as codes, which our messages give (a feed that fails says so in
// one line, not in FFmpeg's lines beside it).
void quietFfmpeg();

}  // namespace lumistage
