#include "core/render/video_file.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/imgutils.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}

#include <algorithm>
#include <cmath>
#include <mutex>

#include "core/base/error.h"
#include "core/base/output_path.h"

namespace lumistage {

namespace {

std::string avError(int code) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(code, text, sizeof text);
  return text;
}

// FFmpeg's own log (libx264's banner and statistics, the muxer's notes) says nothing a user of
// Lumistage needs; its errors come back as codes, and those are in our messages.
void quietFfmpeg() {
  static std::once_flag once;
  std::call_once(once, [] { av_log_set_level(AV_LOG_ERROR); });
}

AVPixelFormat pixelFormatOf(PixelOrder order) {
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

int bytesPerPixel(PixelOrder order) {
  return order == PixelOrder::kRgb || order == PixelOrder::kBgr ? 3 : 4;
}

}  // namespace

VideoCodec videoCodecFor(const std::filesystem::path& file) {
  const std::string extension = lowercaseExtension(file);
  if (extension == ".mp4" || extension == ".mov" || extension == ".mkv") return VideoCodec::kH264;
  if (extension == ".avi") return VideoCodec::kMjpeg;
  throw Error(file.string() +
              ": expected a video file ending in .mp4 or .avi (H.264 in MP4, Motion-JPEG in AVI), "
              "not '" +
              extension + "'");
}

struct VideoFileWriter::Impl {
  std::filesystem::path file;
  std::string name;  // file as text, for messages
  VideoCodec codec = VideoCodec::kH264;
  VideoSpeed speed = VideoSpeed::kQuality;
  std::string warning;
  int width = 0, height = 0;  // of the video: even
  int source_width = 0, source_height = 0;
  double fps = 0;
  int64_t frames = 0;
  bool open = false;  // the header is written, the trailer is not
  AVFormatContext* format = nullptr;
  AVCodecContext* encoder = nullptr;
  AVStream* stream = nullptr;
  AVFrame* frame = nullptr;
  AVPacket* packet = nullptr;
  SwsContext* scaler = nullptr;
  AVPixelFormat scaler_input = AV_PIX_FMT_NONE;

  Error fail(const std::string& what, int code) const {
    return Error(name + ": " + what + " (" + avError(code) + ")");
  }
  // Sends `input` (null: drain) and writes every packet the encoder gives back.
  void encode(const AVFrame* input);
  void openEncoder();
  void release();
};

void VideoFileWriter::Impl::openEncoder() {
  const AVCodec* found = nullptr;
  if (codec == VideoCodec::kMjpeg) {
    found = avcodec_find_encoder(AV_CODEC_ID_MJPEG);
  } else {
    found = avcodec_find_encoder_by_name("libx264");
    if (!found) {
      found = avcodec_find_encoder(AV_CODEC_ID_MPEG4);
      warning = name +
                ": this FFmpeg's libavcodec has no libx264 encoder (H.264): written as MPEG-4 "
                "Part 2 instead (FFmpeg's own encoder; plays everywhere, larger files)";
    }
  }
  if (!found) throw Error(name + ": this FFmpeg's libavcodec has no encoder for the video");
  encoder = avcodec_alloc_context3(found);
  if (!encoder) throw Error(name + ": out of memory for the video encoder");
  const AVRational rate = av_d2q(fps, 1000000);
  encoder->width = width;
  encoder->height = height;
  encoder->time_base = av_inv_q(rate);
  encoder->framerate = rate;
  encoder->pix_fmt = AV_PIX_FMT_YUV420P;
  encoder->sample_aspect_ratio = AVRational{1, 1};
  encoder->colorspace = AVCOL_SPC_SMPTE170M;  // what libswscale converts RGB with: BT.601
  encoder->color_primaries = AVCOL_PRI_SMPTE170M;
  encoder->color_trc = AVCOL_TRC_SMPTE170M;
  AVDictionary* options = nullptr;
  if (codec == VideoCodec::kMjpeg) {
    encoder->color_range = AVCOL_RANGE_JPEG;  // JPEG's full range
    encoder->flags |= AV_CODEC_FLAG_QSCALE;
    encoder->global_quality = FF_QP2LAMBDA * 2;
  } else if (warning.empty()) {
    encoder->color_range = AVCOL_RANGE_MPEG;
    av_dict_set(&options, "preset", speed == VideoSpeed::kLive ? "ultrafast" : "veryfast", 0);
    av_dict_set(&options, "crf", "20", 0);
    av_dict_set(&options, "profile", "high", 0);
    // Live: a key frame every second, each starting a fragment of the MP4 (below).
    if (speed == VideoSpeed::kLive) encoder->gop_size = std::max(1, int(std::lround(fps)));
  } else {
    encoder->color_range = AVCOL_RANGE_MPEG;
    encoder->flags |= AV_CODEC_FLAG_QSCALE;
    encoder->global_quality = FF_QP2LAMBDA * 3;
    encoder->gop_size = 12;
  }
  if (format->oformat->flags & AVFMT_GLOBALHEADER) encoder->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
  const int opened = avcodec_open2(encoder, found, &options);
  av_dict_free(&options);
  if (opened < 0) throw fail(std::string("cannot open the ") + found->name + " encoder", opened);
}

VideoFileWriter::VideoFileWriter(const std::filesystem::path& file, int width, int height,
                                 double fps, std::optional<VideoCodec> codec, VideoSpeed speed)
    : impl_(std::make_unique<Impl>()) {
  quietFfmpeg();
  Impl& v = *impl_;
  v.file = file;
  v.name = file.string();
  if (width < 2 || height < 2)
    throw Error(v.name + ": cannot write a video of " + std::to_string(width) + "x" +
                std::to_string(height) + " (at least 2x2)");
  if (!(fps > 0 && fps <= 1000))
    throw Error(v.name + ": cannot write a video at " + std::to_string(fps) +
                " frames a second (expected 0 to 1000)");
  v.codec = codec ? *codec : videoCodecFor(file);
  v.speed = speed;
  v.source_width = width;
  v.source_height = height;
  v.width = width & ~1;
  v.height = height & ~1;
  v.fps = fps;
  try {
    const char* container = v.codec == VideoCodec::kMjpeg ? "avi" : "mp4";
    int code = avformat_alloc_output_context2(&v.format, nullptr, container, v.name.c_str());
    if (code < 0) throw v.fail(std::string("cannot make a ") + container + " file", code);
    v.openEncoder();
    v.stream = avformat_new_stream(v.format, nullptr);
    if (!v.stream) throw Error(v.name + ": out of memory for the video stream");
    code = avcodec_parameters_from_context(v.stream->codecpar, v.encoder);
    if (code < 0) throw v.fail("cannot describe the video stream", code);
    v.stream->time_base = v.encoder->time_base;  // the muxer may choose its own
    v.stream->avg_frame_rate = v.encoder->framerate;
    v.stream->r_frame_rate = v.encoder->framerate;
    code = avio_open(&v.format->pb, v.name.c_str(), AVIO_FLAG_WRITE);
    if (code < 0) throw v.fail("cannot create the video file", code);
    // Live MP4 is fragmented (a fragment from each key frame): a recording the process never
    // closed (a crash, a power cut) still plays up to its last whole fragment.
    AVDictionary* muxing = nullptr;
    if (v.speed == VideoSpeed::kLive && v.codec == VideoCodec::kH264) {
      av_dict_set(&muxing, "movflags", "frag_keyframe+empty_moov+default_base_moof", 0);
      v.format->flags |= AVFMT_FLAG_FLUSH_PACKETS;  // each fragment to the file when made
    }
    code = avformat_write_header(v.format, &muxing);
    av_dict_free(&muxing);
    if (code < 0) throw v.fail("cannot write the video's header", code);
    v.open = true;
    v.frame = av_frame_alloc();
    v.packet = av_packet_alloc();
    if (!v.frame || !v.packet) throw Error(v.name + ": out of memory for the video's frame");
    v.frame->format = v.encoder->pix_fmt;
    v.frame->width = v.width;
    v.frame->height = v.height;
    v.frame->color_range = v.encoder->color_range;
    code = av_frame_get_buffer(v.frame, 0);
    if (code < 0) throw v.fail("cannot allocate the video's frame", code);
  } catch (...) {
    v.release();
    throw;
  }
}

VideoFileWriter::~VideoFileWriter() {
  try {
    close();
  } catch (const Error&) {
    // Lost: a caller that needs to know calls close().
  }
  impl_->release();
}

void VideoFileWriter::Impl::release() {
  sws_freeContext(scaler);
  scaler = nullptr;
  av_packet_free(&packet);
  av_frame_free(&frame);
  avcodec_free_context(&encoder);
  if (format) {
    if (format->pb) avio_closep(&format->pb);
    avformat_free_context(format);
    format = nullptr;
  }
  open = false;
}

void VideoFileWriter::Impl::encode(const AVFrame* input) {
  int code = avcodec_send_frame(encoder, input);
  if (code < 0) throw fail("cannot encode frame " + std::to_string(frames), code);
  for (;;) {
    code = avcodec_receive_packet(encoder, packet);
    if (code == AVERROR(EAGAIN) || code == AVERROR_EOF) break;
    if (code < 0) throw fail("cannot encode frame " + std::to_string(frames), code);
    av_packet_rescale_ts(packet, encoder->time_base, stream->time_base);
    packet->stream_index = stream->index;
    code = av_interleaved_write_frame(format, packet);  // takes the packet's data; packet is reset
    if (code < 0) throw fail("cannot write the video (disk full?)", code);
  }
  // The file's buffered writes fail late: a full disk shows here, not at the packet.
  if (format->pb->error < 0) throw fail("cannot write the video (disk full?)", format->pb->error);
}

void VideoFileWriter::write(const uint8_t* pixels, PixelOrder order, int stride) {
  Impl& v = *impl_;
  if (!v.open) throw Error(v.name + ": the video is closed; no frame can be added");
  const AVPixelFormat input = pixelFormatOf(order);
  if (!v.scaler || input != v.scaler_input) {
    sws_freeContext(v.scaler);
    // The even part of the image (an odd last column or row is left out), same size: no scaling.
    v.scaler = sws_getContext(v.width, v.height, input, v.width, v.height, v.encoder->pix_fmt,
                              SWS_POINT, nullptr, nullptr, nullptr);
    if (!v.scaler) throw Error(v.name + ": cannot convert its frames to YUV (libswscale)");
    const int full = v.encoder->color_range == AVCOL_RANGE_JPEG;
    const int* bt601 = sws_getCoefficients(SWS_CS_ITU601);
    sws_setColorspaceDetails(v.scaler, bt601, 1, bt601, full, 0, 1 << 16, 1 << 16);
    v.scaler_input = input;
  }
  // The encoder may still hold the last frame (frame threads): then a new buffer, else this one.
  int code = av_frame_make_writable(v.frame);
  if (code < 0) throw v.fail("cannot allocate the video's frame", code);
  const uint8_t* planes[1] = {pixels};
  const int strides[1] = {stride > 0 ? stride : v.source_width * bytesPerPixel(order)};
  sws_scale(v.scaler, planes, strides, 0, v.height, v.frame->data, v.frame->linesize);
  v.frame->pts = v.frames;
  if (v.encoder->flags & AV_CODEC_FLAG_QSCALE) v.frame->quality = v.encoder->global_quality;
  v.encode(v.frame);
  ++v.frames;
}

void VideoFileWriter::close() {
  Impl& v = *impl_;
  if (!v.open) return;
  v.open = false;
  try {
    v.encode(nullptr);  // the frames the encoder still holds
    const int code = av_write_trailer(v.format);
    if (code < 0) throw v.fail("cannot write the video's index (disk full?)", code);
    avio_flush(v.format->pb);
    if (v.format->pb->error < 0)
      throw v.fail("cannot write the video (disk full?)", v.format->pb->error);
    const int closed = avio_closep(&v.format->pb);
    if (closed < 0) throw v.fail("cannot close the video file", closed);
  } catch (...) {
    v.release();
    throw;
  }
  v.release();
}

const std::filesystem::path& VideoFileWriter::file() const {
  return impl_->file;
}
int VideoFileWriter::width() const {
  return impl_->width;
}
int VideoFileWriter::height() const {
  return impl_->height;
}
double VideoFileWriter::fps() const {
  return impl_->fps;
}
int64_t VideoFileWriter::framesWritten() const {
  return impl_->frames;
}
VideoCodec VideoFileWriter::codec() const {
  return impl_->codec;
}
std::string VideoFileWriter::encoderName() const {
  if (impl_->codec == VideoCodec::kMjpeg) return "mjpeg";
  return impl_->warning.empty() ? "libx264" : "mpeg4";
}
const std::string& VideoFileWriter::warning() const {
  return impl_->warning;
}

VideoFileInfo probeVideoFile(const std::filesystem::path& file) {
  quietFfmpeg();
  const std::string name = file.string();
  AVFormatContext* format = nullptr;
  int code = avformat_open_input(&format, name.c_str(), nullptr, nullptr);
  if (code < 0) throw Error(name + ": cannot open the video (" + avError(code) + ")");
  struct Close {
    AVFormatContext** format;
    ~Close() { avformat_close_input(format); }
  } close{&format};
  code = avformat_find_stream_info(format, nullptr);
  if (code < 0) throw Error(name + ": cannot read the video's streams (" + avError(code) + ")");
  const int index = av_find_best_stream(format, AVMEDIA_TYPE_VIDEO, -1, -1, nullptr, 0);
  if (index < 0) throw Error(name + ": no video stream in it");
  const AVStream* stream = format->streams[index];
  VideoFileInfo info;
  info.width = stream->codecpar->width;
  info.height = stream->codecpar->height;
  const AVRational rate =
      stream->avg_frame_rate.num > 0 ? stream->avg_frame_rate : stream->r_frame_rate;
  info.fps = rate.den > 0 ? av_q2d(rate) : 0;
  info.codec = avcodec_get_name(stream->codecpar->codec_id);
  info.container = format->iformat->name;
  AVPacket* packet = av_packet_alloc();
  if (!packet) throw Error(name + ": out of memory reading the video");
  while (av_read_frame(format, packet) >= 0) {
    info.frames += packet->stream_index == index;
    av_packet_unref(packet);
  }
  av_packet_free(&packet);
  return info;
}

int64_t copyVideoFile(const std::filesystem::path& in, const std::filesystem::path& out) {
  quietFfmpeg();
  const std::string name = in.string(), out_name = out.string();
  AVFormatContext* input = nullptr;
  AVFormatContext* output = nullptr;
  AVPacket* packet = av_packet_alloc();
  struct Close {
    AVFormatContext** input;
    AVFormatContext** output;
    AVPacket** packet;
    ~Close() {
      av_packet_free(packet);
      avformat_close_input(input);
      if (*output) {
        if ((*output)->pb) avio_closep(&(*output)->pb);
        avformat_free_context(*output);
      }
    }
  } close{&input, &output, &packet};
  auto fail = [](const std::string& file, const std::string& what, int code) {
    return Error(file + ": " + what + " (" + avError(code) + ")");
  };
  int code = avformat_open_input(&input, name.c_str(), nullptr, nullptr);
  if (code < 0) throw fail(name, "cannot open the video", code);
  code = avformat_find_stream_info(input, nullptr);
  if (code < 0) throw fail(name, "cannot read the video's streams", code);
  const int index = av_find_best_stream(input, AVMEDIA_TYPE_VIDEO, -1, -1, nullptr, 0);
  if (index < 0) throw Error(name + ": no video stream in it");
  const AVStream* from = input->streams[index];
  const char* container = videoCodecFor(out) == VideoCodec::kMjpeg ? "avi" : "mp4";
  code = avformat_alloc_output_context2(&output, nullptr, container, out_name.c_str());
  if (code < 0) throw fail(out_name, std::string("cannot make a ") + container + " file", code);
  AVStream* to = avformat_new_stream(output, nullptr);
  if (!to || !packet) throw Error(out_name + ": out of memory for the video stream");
  code = avcodec_parameters_copy(to->codecpar, from->codecpar);
  if (code < 0) throw fail(out_name, "cannot describe the video stream", code);
  to->codecpar->codec_tag = 0;  // the new container's own
  to->time_base = from->time_base;
  to->avg_frame_rate = from->avg_frame_rate;
  code = avio_open(&output->pb, out_name.c_str(), AVIO_FLAG_WRITE);
  if (code < 0) throw fail(out_name, "cannot create the video file", code);
  code = avformat_write_header(output, nullptr);
  if (code < 0) throw fail(out_name, "cannot write the video's header", code);
  int64_t frames = 0;
  while (av_read_frame(input, packet) >= 0) {
    if (packet->stream_index != index) {
      av_packet_unref(packet);
      continue;
    }
    av_packet_rescale_ts(packet, from->time_base, to->time_base);
    packet->stream_index = 0;
    packet->pos = -1;
    code = av_interleaved_write_frame(output, packet);
    if (code < 0) throw fail(out_name, "cannot write the video (disk full?)", code);
    ++frames;
  }
  code = av_write_trailer(output);
  if (code < 0 || output->pb->error < 0)
    throw fail(out_name, "cannot write the video (disk full?)",
               code < 0 ? code : output->pb->error);
  code = avio_closep(&output->pb);
  if (code < 0) throw fail(out_name, "cannot close the video file", code);
  return frames;
}

}  // namespace lumistage
