#include "core/render/video_encoder.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/imgutils.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}

#include <algorithm>
#include <cmath>
#include <mutex>

#include "core/base/error.h"

namespace lumistage {

std::string ffmpegError(int code) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(code, text, sizeof text);
  return text;
}

void quietFfmpeg() {
  static std::once_flag once;
  std::call_once(once, [] { av_log_set_level(AV_LOG_FATAL); });
}

namespace {

// FFmpeg's pixel format of packed pixels in `order`.
AVPixelFormat avPixelFormatOf(PixelOrder order) {
  switch (order) {
    case PixelOrder::kRgb:
      return AV_PIX_FMT_RGB24;
    case PixelOrder::kRgba:
      return AV_PIX_FMT_RGBA;
    case PixelOrder::kBgr:
      return AV_PIX_FMT_BGR24;
    case PixelOrder::kBgra:
      return AV_PIX_FMT_BGRA;
  }
  return AV_PIX_FMT_RGB24;
}

}  // namespace

VideoEncoder::VideoEncoder(std::string name, VideoCodec codec, VideoSpeed speed, int width,
                           int height, double fps, bool global_header)
    : name_(std::move(name)), codec_(codec), width_(width & ~1), height_(height & ~1) {
  quietFfmpeg();
  auto fail = [this](const std::string& what, int code) {
    return Error(name_ + ": " + what + " (" + ffmpegError(code) + ")");
  };
  const AVCodec* found = nullptr;
  if (codec == VideoCodec::kMjpeg) {
    found = avcodec_find_encoder(AV_CODEC_ID_MJPEG);
  } else {
    found = avcodec_find_encoder_by_name("libx264");
    if (!found) {
      found = avcodec_find_encoder(AV_CODEC_ID_MPEG4);
      warning_ = name_ +
                 ": this FFmpeg's libavcodec has no libx264 encoder (H.264): written as MPEG-4 "
                 "Part 2 instead (FFmpeg's own encoder; plays everywhere, larger files)";
    }
  }
  if (!found) throw Error(name_ + ": this FFmpeg's libavcodec has no encoder for the video");
  encoder_ = avcodec_alloc_context3(found);
  if (!encoder_) throw Error(name_ + ": out of memory for the video encoder");
  const AVRational rate = av_d2q(fps, 1000000);
  const int gop = std::max(1, int(std::lround(fps)));  // a key frame a second
  encoder_->width = width_;
  encoder_->height = height_;
  // A feed's pictures are stamped by the clock, in MPEG-TS's own 90 kHz; a file's by their count.
  encoder_->time_base = speed == VideoSpeed::kFeed ? AVRational{1, 90000} : av_inv_q(rate);
  encoder_->framerate = rate;
  encoder_->pix_fmt = AV_PIX_FMT_YUV420P;
  encoder_->sample_aspect_ratio = AVRational{1, 1};
  encoder_->colorspace = AVCOL_SPC_SMPTE170M;  // what libswscale converts RGB with: BT.601
  encoder_->color_primaries = AVCOL_PRI_SMPTE170M;
  encoder_->color_trc = AVCOL_TRC_SMPTE170M;
  AVDictionary* options = nullptr;
  if (codec == VideoCodec::kMjpeg) {
    encoder_->color_range = AVCOL_RANGE_JPEG;  // JPEG's full range
    encoder_->flags |= AV_CODEC_FLAG_QSCALE;
    encoder_->global_quality = FF_QP2LAMBDA * 2;
  } else if (warning_.empty()) {
    encoder_->color_range = AVCOL_RANGE_MPEG;
    av_dict_set(&options, "preset", speed == VideoSpeed::kQuality ? "veryfast" : "ultrafast", 0);
    av_dict_set(&options, "profile", "high", 0);
    if (speed == VideoSpeed::kFeed) {
      // Each picture out as soon as it is in (no look-ahead, no B-frames, threads on slices of
      // one picture), at a rate a network carries: capped near a tenth of a bit a pixel.
      av_dict_set(&options, "tune", "zerolatency", 0);
      av_dict_set(&options, "crf", "23", 0);
      const int64_t cap = std::max<int64_t>(1000000, int64_t(0.12 * width_ * height_ * fps));
      encoder_->rc_max_rate = cap;
      encoder_->rc_buffer_size = int(std::min<int64_t>(cap, INT32_MAX));
      encoder_->max_b_frames = 0;
    } else {
      av_dict_set(&options, "crf", "20", 0);
    }
    // Live and feeds: a key frame every second (a fragment of a live MP4 starts at each; a
    // receiver that joins a feed shows pictures from the next).
    if (speed != VideoSpeed::kQuality) encoder_->gop_size = gop;
  } else {
    encoder_->color_range = AVCOL_RANGE_MPEG;
    encoder_->flags |= AV_CODEC_FLAG_QSCALE;
    encoder_->global_quality = FF_QP2LAMBDA * 3;
    encoder_->gop_size = speed == VideoSpeed::kFeed ? gop : 12;
    if (speed == VideoSpeed::kFeed) encoder_->max_b_frames = 0;
  }
  if (global_header) encoder_->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
  try {
    const int opened = avcodec_open2(encoder_, found, &options);
    av_dict_free(&options);
    if (opened < 0) throw fail(std::string("cannot open the ") + found->name + " encoder", opened);
    frame_ = av_frame_alloc();
    packet_ = av_packet_alloc();
    if (!frame_ || !packet_) throw Error(name_ + ": out of memory for the video's frame");
    frame_->format = encoder_->pix_fmt;
    frame_->width = width_;
    frame_->height = height_;
    frame_->color_range = encoder_->color_range;
    const int code = av_frame_get_buffer(frame_, 0);
    if (code < 0) throw fail("cannot allocate the video's frame", code);
  } catch (...) {
    release();
    throw;
  }
}

VideoEncoder::~VideoEncoder() {
  release();
}

YuvConverter::~YuvConverter() {
  sws_freeContext(scaler_);
}

void YuvConverter::convert(const uint8_t* pixels, PixelOrder order, int source_width,
                           int source_height, int stride, int width, int height, int yuv_format,
                           bool full_range, uint8_t* const planes[], const int strides[],
                           const std::string& name) {
  const AVPixelFormat input = avPixelFormatOf(order);
  // The same size: the even part of the image (an odd last column or row is left out), copied;
  // another: scaled.
  const bool same = (source_width & ~1) == width && (source_height & ~1) == height;
  const int from_width = same ? width : source_width, from_height = same ? height : source_height;
  if (!scaler_ || input != input_ || from_width != from_width_ || from_height != from_height_ ||
      width != width_ || height != height_) {
    sws_freeContext(scaler_);
    scaler_ =
        sws_getContext(from_width, from_height, input, width, height, AVPixelFormat(yuv_format),
                       same ? SWS_POINT : SWS_BILINEAR, nullptr, nullptr, nullptr);
    input_ = -1;
    if (!scaler_) throw Error(name + ": cannot convert its frames to YUV (libswscale)");
    const int* bt601 = sws_getCoefficients(SWS_CS_ITU601);
    sws_setColorspaceDetails(scaler_, bt601, 1, bt601, full_range, 0, 1 << 16, 1 << 16);
    input_ = input;
    from_width_ = from_width;
    from_height_ = from_height;
    width_ = width;
    height_ = height;
  }
  const uint8_t* source[1] = {pixels};
  const int source_stride[1] = {stride > 0 ? stride : source_width * bytesPerPixel(order)};
  sws_scale(scaler_, source, source_stride, 0, from_height, planes, strides);
}

void VideoEncoder::release() {
  av_packet_free(&packet_);
  av_frame_free(&frame_);
  avcodec_free_context(&encoder_);
}

void VideoEncoder::send(const uint8_t* pixels, PixelOrder order, int source_width,
                        int source_height, int stride, int64_t pts) {
  // The encoder may still hold the last frame (frame threads): then a new buffer, else this one.
  int code = av_frame_make_writable(frame_);
  if (code < 0)
    throw Error(name_ + ": cannot allocate the video's frame (" + ffmpegError(code) + ")");
  converter_.convert(pixels, order, source_width, source_height, stride, width_, height_,
                     encoder_->pix_fmt, encoder_->color_range == AVCOL_RANGE_JPEG, frame_->data,
                     frame_->linesize, name_);
  frame_->pts = pts;
  if (encoder_->flags & AV_CODEC_FLAG_QSCALE) frame_->quality = encoder_->global_quality;
  code = avcodec_send_frame(encoder_, frame_);
  if (code < 0) throw Error(name_ + ": cannot encode a frame (" + ffmpegError(code) + ")");
}

void VideoEncoder::sendEnd() {
  const int code = avcodec_send_frame(encoder_, nullptr);
  if (code < 0 && code != AVERROR_EOF)
    throw Error(name_ + ": cannot end the video's encoding (" + ffmpegError(code) + ")");
}

AVPacket* VideoEncoder::receive() {
  const int code = avcodec_receive_packet(encoder_, packet_);
  if (code == AVERROR(EAGAIN) || code == AVERROR_EOF) return nullptr;
  if (code < 0) throw Error(name_ + ": cannot encode a frame (" + ffmpegError(code) + ")");
  return packet_;
}

std::string VideoEncoder::encoderName() const {
  if (codec_ == VideoCodec::kMjpeg) return "mjpeg";
  return warning_.empty() ? "libx264" : "mpeg4";
}

}  // namespace lumistage
