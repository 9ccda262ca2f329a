#include "core/render/view_recorder.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <string_view>
#include <vector>

#include "core/base/error.h"
#include "core/base/output_path.h"
#include "core/net/message_types.h"
#include "core/render/video_file.h"

namespace lumistage {

std::filesystem::path partialVideoPath(const std::filesystem::path& file) {
  return file.parent_path() / (file.stem().string() + ".partial" + file.extension().string());
}

namespace {

// NAME-recovered.avi (k = 1), NAME-recovered-K.avi, beside NAME.partial.avi or NAME.partial-J.avi.
std::filesystem::path recoveredVideoPath(const std::filesystem::path& partial, int k) {
  std::string stem = partial.stem().string();
  if (const size_t dot = stem.rfind(".partial"); dot != std::string::npos) stem.resize(dot);
  return partial.parent_path() /
         (stem + "-recovered" + (k > 1 ? "-" + std::to_string(k) : std::string()) +
          partial.extension().string());
}

}  // namespace

std::filesystem::path recoveredVideoPath(const std::filesystem::path& partial) {
  std::error_code error;
  int k = 1;
  while (std::filesystem::exists(recoveredVideoPath(partial, k), error)) ++k;
  return recoveredVideoPath(partial, k);
}

bool wasRecovered(const std::filesystem::path& partial) {
  std::error_code error;
  const auto changed = std::filesystem::last_write_time(partial, error);
  if (error) return false;
  for (int k = 1;; ++k) {
    const auto made = std::filesystem::last_write_time(recoveredVideoPath(partial, k), error);
    if (error) return false;
    if (made >= changed) return true;
  }
}

Status finishPartialVideo(const std::filesystem::path& partial, const std::filesystem::path& file,
                          int64_t frames) {
  int64_t read_back = 0;
  try {
    read_back = probeVideoFile(partial).frames;
  } catch (const Error&) {
    // Not even a header: no frame reads back.
  }
  if (read_back != frames) {
    return Status::failure(file.string() + ": the video reads back " + std::to_string(read_back) +
                           " of its " + std::to_string(frames) + " frames (disk full?)");
  }
  std::error_code error;
  std::filesystem::rename(partial, file, error);
  if (error) {
    return Status::failure(file.string() + ": cannot put the video in its place (" +
                           error.message() + ")");
  }
  return {};
}

namespace {

uint32_t word(const char* p) {
  uint32_t v = 0;
  std::memcpy(&v, p, 4);
  return v;  // little-endian, as RIFF is (and as this machine is)
}
uint32_t word(const std::string& d, size_t at) {
  return word(d.data() + at);
}
void putWord(std::string& d, size_t at, uint32_t v) {
  std::memcpy(d.data() + at, &v, 4);
}
bool isCode(const std::string& d, size_t at, const char* code) {
  return d.compare(at, 4, code) == 0;
}

}  // namespace

namespace {

// A live MP4 is fragmented (video_file.h): its whole fragments are copied into a plain MP4.
RecoveredVideo recoverPartialMp4(const std::filesystem::path& partial,
                                 const std::filesystem::path& out) {
  std::error_code error;
  if (std::filesystem::exists(out, error))
    throw Error(out.string() + ": exists; recover " + partial.string() + " under another name");
  RecoveredVideo r;
  try {
    r.fps = probeVideoFile(partial).fps;
  } catch (const Error& e) {
    throw Error(std::string(e.what()) + "; not a recording of the view that can be recovered");
  }
  // Written beside `out`, then renamed: a recovery cut short leaves nothing under the name.
  const std::filesystem::path temporary = partialVideoPath(out);
  try {
    r.frames = copyVideoFile(partial, temporary);
  } catch (const Error&) {
    std::filesystem::remove(temporary, error);
    throw;
  }
  if (r.frames == 0) {
    std::filesystem::remove(temporary, error);
    throw Error(partial.string() + ": not one whole frame in it");
  }
  std::filesystem::rename(temporary, out, error);
  if (error) {
    std::filesystem::remove(temporary, error);
    throw Error(out.string() + ": cannot put the video in its place");
  }
  return r;
}

}  // namespace

RecoveredVideo recoverPartialVideo(const std::filesystem::path& partial,
                                   const std::filesystem::path& out) {
  if (lowercaseExtension(partial) == ".mp4") return recoverPartialMp4(partial, out);
  const std::string name = partial.string();
  auto fail = [&](const std::string& why) {
    return Error(name + ": " + why + "; not a recording of the view that can be recovered");
  };
  std::ifstream in(partial, std::ios::binary);
  if (!in) throw Error(name + ": cannot read it");
  std::error_code error;
  const uint64_t file_size = std::filesystem::file_size(partial, error);
  if (error) throw Error(name + ": cannot read it (" + error.message() + ")");
  // The headers: RIFF AVI, then LIST hdrl, JUNK to the first 4 KB, LIST movi (OpenCV's writer);
  // the sizes of RIFF and movi stay 0 until the recording closes.
  std::string head(size_t(std::min<uint64_t>(file_size, 1 << 16)), '\0');
  in.read(head.data(), std::streamsize(head.size()));
  if (head.size() < 12 || !isCode(head, 0, "RIFF") || !isCode(head, 8, "AVI "))
    throw fail("not an AVI file");
  size_t at = 12, hdrl = 0, movi = 0;
  while (at + 12 <= head.size()) {
    if (isCode(head, at, "LIST") && isCode(head, at + 8, "hdrl")) hdrl = at;
    if (isCode(head, at, "LIST") && isCode(head, at + 8, "movi")) {
      movi = at;
      break;
    }
    const uint32_t size = word(head, at + 4);
    at += 8 + size_t(size) + (size & 1);
  }
  if (hdrl == 0 || movi == 0) throw fail("no header list and frame list where they belong");
  if (word(head, movi + 4) != 0 || word(head, 4) != 0)
    throw fail("it was closed: its sizes are written");
  head.resize(movi + 12);  // what comes before the frames
  const size_t avih = head.find("avih", hdrl), strh = head.find("strh", hdrl);
  if (avih == std::string::npos || strh == std::string::npos || avih + 64 > movi ||
      strh + 64 > movi || !isCode(head, strh + 8, "vids") || !isCode(head, strh + 12, "MJPG"))
    throw fail("no Motion-JPEG video stream in its header");
  const size_t dmlh = head.find("dmlh", hdrl);
  RecoveredVideo r;
  const uint32_t scale = word(head, strh + 8 + 20), rate = word(head, strh + 8 + 24);
  r.fps = scale > 0 ? double(rate) / scale : 0;

  // The frames: whole chunks holding a whole JPEG image (its start marker, and its end marker in
  // the chunk's last bytes), up to the first that is not: cut by the end of the file, or zeros
  // where the disk never got the data. Only their headers and ends are read.
  std::vector<std::pair<uint64_t, uint32_t>> frames;  // chunk offset, data size
  uint64_t end = movi + 12;
  for (;;) {
    char chunk[10], tail[16];
    in.clear();
    in.seekg(std::streamoff(end));
    if (!in.read(chunk, 10)) break;
    const std::string code(chunk, 4);
    const uint32_t size = word(chunk + 4);
    if ((code != "00dc" && code != "00db") || size < 16 || end + 8 + size > file_size ||
        uint8_t(chunk[8]) != 0xff || uint8_t(chunk[9]) != 0xd8)
      break;
    in.seekg(std::streamoff(end + 8 + size - 16));
    if (!in.read(tail, 16)) break;
    if (std::string_view(tail, 16).find("\xff\xd9") == std::string_view::npos) break;
    frames.emplace_back(end, size);
    end += 8 + uint64_t(size) + (size & 1);
  }
  r.frames = int64_t(frames.size());
  r.bytes_cut = int64_t(file_size - end);
  if (frames.empty()) throw fail("not one whole frame in it");
  if (end + 8 + 16 * frames.size() > 0xffffffffu)
    throw fail("over 4 GB, more than an AVI's index can hold");
  if (std::filesystem::exists(out, error))
    throw Error(out.string() + ": exists; recover " + name + " under another name");

  // What closing would have written: the frames as they are, their index, the sizes and counts.
  const uint32_t n = uint32_t(frames.size());
  constexpr uint32_t kHasIndex = 0x10, kKeyFrame = 0x10;
  putWord(head, avih + 8 + 12, word(head, avih + 8 + 12) | kHasIndex);  // dwFlags
  putWord(head, avih + 8 + 16, n);                                      // dwTotalFrames
  putWord(head, strh + 8 + 32, n);                                      // dwLength
  if (dmlh != std::string::npos && dmlh + 12 <= movi) putWord(head, dmlh + 8, n);
  putWord(head, movi + 4, uint32_t(end - movi - 8));
  std::string index = "idx1";
  index.resize(8 + 16 * size_t(n));
  putWord(index, 4, 16 * n);
  for (uint32_t i = 0; i < n; ++i) {
    const size_t e = 8 + 16 * size_t(i);
    index.replace(e, 4, "00dc");
    putWord(index, e + 4, kKeyFrame);
    putWord(index, e + 8, uint32_t(frames[i].first - (movi + 8)));  // from the list's 'movi'
    putWord(index, e + 12, frames[i].second);
  }
  putWord(head, 4, uint32_t(end + index.size() - 8));
  // Written beside `out`, then renamed: a recovery cut short leaves nothing under the name.
  const std::filesystem::path temporary = out.string() + ".recovering";
  {
    std::ofstream video(temporary, std::ios::binary | std::ios::trunc);
    if (!video) throw Error(out.string() + ": cannot write there");
    video.write(head.data(), std::streamsize(head.size()));
    std::vector<char> buffer(1 << 20);
    in.clear();
    in.seekg(std::streamoff(movi + 12));
    for (uint64_t left = end - (movi + 12); left > 0 && video;) {
      const size_t step = size_t(std::min<uint64_t>(left, buffer.size()));
      if (!in.read(buffer.data(), std::streamsize(step))) break;
      video.write(buffer.data(), std::streamsize(step));
      left -= step;
    }
    video.write(index.data(), std::streamsize(index.size()));
    video.flush();
    if (!video || uint64_t(video.tellp()) != end + index.size()) {
      video.close();
      std::filesystem::remove(temporary, error);
      throw Error(out.string() + ": cannot write the whole video there (disk full?)");
    }
  }
  std::filesystem::rename(temporary, out, error);
  if (error) {
    std::filesystem::remove(temporary, error);
    throw Error(out.string() + ": cannot put the video in its place");
  }
  return r;
}

struct ViewRecorder::Impl {
  std::filesystem::path file, partial, leftover;
  std::string error;
  double fps = 30;
  int max_gap = 30;
  bool mp4 = false;        // H.264 in MP4 through FFmpeg, else OpenCV's Motion-JPEG AVI
  cv::VideoWriter writer;  // .avi
  std::unique_ptr<VideoFileWriter> video;  // .mp4
  bool closed = false;
  int width = 0, height = 0;
  int64_t last_id = -1, written = 0;
  cv::Mat converted, scaled, last;  // last: the previous frame as written (BGR; RGBA for MP4)

  bool isOpen() const { return mp4 ? video != nullptr : writer.isOpened(); }
  void open(int width, int height);
  void write(const cv::Mat& frame);
};

void ViewRecorder::Impl::open(int first_width, int first_height) {
  // Opened with the first image, whose size the video keeps.
  if (mp4) {
    video = std::make_unique<VideoFileWriter>(partial, first_width, first_height, fps,
                                              VideoCodec::kH264, VideoSpeed::kLive);
    if (!video->warning().empty()) spdlog::warn("{}", video->warning());
  } else {
    // OpenCV's own MJPEG writer (no FFmpeg): the same on every machine, and the layout that
    // recoverPartialVideo reads.
    writer.open(partial.string(), cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'),
                fps, cv::Size(first_width, first_height));
    if (!writer.isOpened()) throw Error(file.string() + ": cannot write the view's video there");
  }
  width = first_width;
  height = first_height;
}

void ViewRecorder::Impl::write(const cv::Mat& frame) {
  if (mp4) {
    try {
      video->write(frame.data, PixelOrder::kRgba, int(frame.step[0]));
    } catch (const Error& e) {  // names the partial file: said under the recording's name
      throw Error(file.string() + ": the recording stops: " + e.what());
    }
  } else {
    writer.write(frame);
  }
}

ViewRecorder::ViewRecorder(const std::filesystem::path& file, double fps, int max_gap_frames)
    : impl_(std::make_unique<Impl>()) {
  if (!(fps > 0 && fps <= 1000))
    throw Error(file.string() + ": cannot record the view at " + std::to_string(fps) +
                " frames a second (expected 0 to 1000)");
  const std::string extension = lowercaseExtension(file);
  if (extension != ".avi" && extension != ".mp4")
    throw Error(file.string() +
                ": the view is recorded as H.264 in an MP4 or Motion-JPEG in an AVI: name it .mp4 "
                "or .avi");
  const std::filesystem::path folder = file.has_parent_path() ? file.parent_path() : ".";
  std::error_code error;
  if (!std::filesystem::is_directory(folder, error))
    throw Error(file.string() + ": cannot record the view: no folder " + folder.string());
  if (std::filesystem::is_directory(file, error))
    throw Error(file.string() + ": cannot record the view: a folder has that name");
  impl_->file = file;
  impl_->partial = partialVideoPath(file);
  // Left by a recording that never closed: kept for recoverPartialVideo, recorded beside.
  for (int k = 2; std::filesystem::exists(impl_->partial, error); ++k) {
    if (impl_->leftover.empty()) impl_->leftover = impl_->partial;
    impl_->partial = file.parent_path() / (file.stem().string() + ".partial-" + std::to_string(k) +
                                           file.extension().string());
  }
  impl_->mp4 = extension == ".mp4";
  impl_->fps = fps;
  impl_->max_gap = std::max(0, max_gap_frames);
}

ViewRecorder::~ViewRecorder() {
  close();
}

bool ViewRecorder::add(int64_t frame_id, int width, int height, std::span<const uint8_t> rgba) {
  Impl& r = *impl_;
  if (r.closed || width <= 0 || height <= 0 || rgba.size() < size_t(width) * height * 4)
    return false;
  // Older than the last: left out; but far older (kFrameIdWindow), the cameras restarted and the
  // studio followed their ids back: the recording goes on from there (it stopped for good).
  if (r.last_id >= 0 && frame_id <= r.last_id) {
    if (frame_id >= r.last_id - kFrameIdWindow) return false;
    r.last_id = -1;
  }
  if (!r.isOpen()) r.open(width, height);
  // MP4: FFmpeg takes RGBA as it is; OpenCV's AVI writer wants BGR.
  const cv::Mat image(height, width, CV_8UC4, const_cast<uint8_t*>(rgba.data()));
  if (!r.mp4) cv::cvtColor(image, r.converted, cv::COLOR_RGBA2BGR);
  const cv::Mat* frame = r.mp4 ? &image : &r.converted;
  if (width != r.width || height != r.height) {
    cv::resize(*frame, r.scaled, cv::Size(r.width, r.height), 0, 0, cv::INTER_AREA);
    frame = &r.scaled;
  }
  // The frames skipped since the last one hold the last image (the new one when too long a gap).
  const int64_t skipped = r.last_id >= 0 ? frame_id - r.last_id - 1 : 0;
  if (skipped > 0 && skipped <= r.max_gap) {
    for (int64_t k = 0; k < skipped; ++k) {
      r.write(r.last);
      ++r.written;
    }
  }
  r.write(*frame);
  frame->copyTo(r.last);
  ++r.written;
  r.last_id = frame_id;
  // OpenCV's writer drops write errors (FFmpeg's throw): the disk's room is watched too.
  if (r.written % kFreeCheckFrames == 0) {
    std::error_code error;
    const std::filesystem::space_info space = std::filesystem::space(r.partial, error);
    if (!error && space.available < uint64_t(kMinFreeBytes))
      throw Error(r.file.string() + ": the disk is full (" + std::to_string(space.available >> 20) +
                  " MB left): the recording stops here, what it holds is kept");
  }
  return true;
}

bool ViewRecorder::close() {
  Impl& r = *impl_;
  if (r.closed) return r.error.empty();
  r.closed = true;
  if (!r.isOpen()) return true;  // nothing recorded: no file
  if (r.mp4) {
    try {
      r.video->close();
    } catch (const Error& e) {
      r.error = e.what();
    }
    r.video.reset();
  } else {
    r.writer.release();
  }
  if (r.error.empty()) r.error = finishPartialVideo(r.partial, r.file, r.written).error();
  if (!r.error.empty()) {
    r.error += "; what was written is kept as " + r.partial.string() +
               " (lumistage video recover makes a video of its whole frames)";
  }
  return r.error.empty();
}

Status ViewRecorder::status() const {
  return impl_->error.empty() ? Status() : Status::failure(impl_->error);
}

const std::filesystem::path& ViewRecorder::file() const {
  return impl_->file;
}
const std::filesystem::path& ViewRecorder::partialFile() const {
  return impl_->partial;
}
const std::filesystem::path& ViewRecorder::leftover() const {
  return impl_->leftover;
}
std::string ViewRecorder::leftoverNotice() const {
  const std::string left = impl_->leftover.string();
  if (left.empty()) return {};
  return left + ", left by a recording that never closed, is kept (lumistage video recover " +
         left + " makes a video of it); this one is recorded beside it";
}
int64_t ViewRecorder::framesWritten() const {
  return impl_->written;
}
double ViewRecorder::fps() const {
  return impl_->fps;
}
int ViewRecorder::width() const {
  return impl_->width;
}
int ViewRecorder::height() const {
  return impl_->height;
}

}  // namespace lumistage
