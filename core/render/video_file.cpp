#include "core/render/video_file.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
}

#include "core/base/error.h"
#include "core/base/output_path.h"
#include "core/render/video_encoder.h"

namespace lumistage {

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
  std::string encoder_name, warning;  // kept when closed
  int source_width = 0, source_height = 0;
  double fps = 0;
  int64_t frames = 0;
  bool open = false;  // the header is written, the trailer is not
  AVFormatContext* format = nullptr;
  std::unique_ptr<VideoEncoder> encoder;
  AVStream* stream = nullptr;

  Error fail(const std::string& what, int code) const {
    return Error(name + ": " + what + " (" + ffmpegError(code) + ")");
  }
  // Writes every packet the encoder gives back.
  void writePackets();
  void release();
};

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
  // A file's frames are stamped by their count: a feed's clock stamps are for feeds alone.
  v.speed = speed == VideoSpeed::kFeed ? VideoSpeed::kLive : speed;
  v.source_width = width;
  v.source_height = height;
  v.fps = fps;
  try {
    const char* container = v.codec == VideoCodec::kMjpeg ? "avi" : "mp4";
    int code = avformat_alloc_output_context2(&v.format, nullptr, container, v.name.c_str());
    if (code < 0) throw v.fail(std::string("cannot make a ") + container + " file", code);
    v.encoder = std::make_unique<VideoEncoder>(v.name, v.codec, v.speed, width, height, fps,
                                               v.format->oformat->flags & AVFMT_GLOBALHEADER);
    v.encoder_name = v.encoder->encoderName();
    v.warning = v.encoder->warning();
    const AVCodecContext* encoder = v.encoder->context();
    v.stream = avformat_new_stream(v.format, nullptr);
    if (!v.stream) throw Error(v.name + ": out of memory for the video stream");
    code = avcodec_parameters_from_context(v.stream->codecpar, encoder);
    if (code < 0) throw v.fail("cannot describe the video stream", code);
    v.stream->time_base = encoder->time_base;  // the muxer may choose its own
    v.stream->avg_frame_rate = encoder->framerate;
    v.stream->r_frame_rate = encoder->framerate;
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
  encoder.reset();
  if (format) {
    if (format->pb) avio_closep(&format->pb);
    avformat_free_context(format);
    format = nullptr;
  }
  open = false;
}

void VideoFileWriter::Impl::writePackets() {
  const AVRational from = encoder->context()->time_base;
  while (AVPacket* packet = encoder->receive()) {
    av_packet_rescale_ts(packet, from, stream->time_base);
    packet->stream_index = stream->index;
    const int code = av_interleaved_write_frame(format, packet);  // takes the packet's data
    if (code < 0) throw fail("cannot write the video (disk full?)", code);
  }
  // The file's buffered writes fail late: a full disk shows here, not at the packet.
  if (format->pb->error < 0) throw fail("cannot write the video (disk full?)", format->pb->error);
}

void VideoFileWriter::write(const uint8_t* pixels, PixelOrder order, int stride) {
  Impl& v = *impl_;
  if (!v.open) throw Error(v.name + ": the video is closed; no frame can be added");
  v.encoder->send(pixels, order, v.source_width, v.source_height, stride, v.frames);
  v.writePackets();
  ++v.frames;
}

void VideoFileWriter::close() {
  Impl& v = *impl_;
  if (!v.open) return;
  v.open = false;
  try {
    v.encoder->sendEnd();  // the frames the encoder still holds
    v.writePackets();
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
  return impl_->source_width & ~1;
}
int VideoFileWriter::height() const {
  return impl_->source_height & ~1;
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
  return impl_->encoder_name;
}
const std::string& VideoFileWriter::warning() const {
  return impl_->warning;
}

VideoFileInfo probeVideoFile(const std::filesystem::path& file) {
  quietFfmpeg();
  const std::string name = file.string();
  AVFormatContext* format = nullptr;
  int code = avformat_open_input(&format, name.c_str(), nullptr, nullptr);
  if (code < 0) throw Error(name + ": cannot open the video (" + ffmpegError(code) + ")");
  struct Close {
    AVFormatContext** format;
    ~Close() { avformat_close_input(format); }
  } close{&format};
  code = avformat_find_stream_info(format, nullptr);
  if (code < 0) throw Error(name + ": cannot read the video's streams (" + ffmpegError(code) + ")");
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
    return Error(file + ": " + what + " (" + ffmpegError(code) + ")");
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
