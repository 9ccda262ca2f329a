#include "core/render/view_recorder.h"

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "core/base/error.h"
#include "core/base/output_path.h"
#include "core/net/message_codec.h"

namespace lumistage {

std::filesystem::path partialVideoPath(const std::filesystem::path& file) {
  return file.parent_path() / (file.stem().string() + ".partial" + file.extension().string());
}

std::string finishPartialVideo(const std::filesystem::path& partial,
                               const std::filesystem::path& file, int64_t frames, int api) {
  cv::VideoCapture check(partial.string(), api);
  const int64_t read_back = check.isOpened() ? int64_t(check.get(cv::CAP_PROP_FRAME_COUNT)) : 0;
  check.release();
  if (read_back != frames) {
    return file.string() + ": the video reads back " + std::to_string(read_back) + " of its " +
           std::to_string(frames) + " frames (disk full?)";
  }
  std::error_code error;
  std::filesystem::rename(partial, file, error);
  if (error) return file.string() + ": cannot put the video in its place (" + error.message() + ")";
  return {};
}

struct ViewRecorder::Impl {
  std::filesystem::path file, partial;
  std::string error;
  double fps = 30;
  int max_gap = 30;
  cv::VideoWriter writer;
  bool closed = false;
  int width = 0, height = 0;
  int64_t last_id = -1, written = 0;
  cv::Mat bgr, scaled, last;  // last: the previous frame as written
};

ViewRecorder::ViewRecorder(const std::filesystem::path& file, double fps, int max_gap_frames)
    : impl_(std::make_unique<Impl>()) {
  if (!(fps > 0 && fps <= 1000))
    throw Error(file.string() + ": cannot record the view at " + std::to_string(fps) +
                " frames a second (expected 0 to 1000)");
  if (lowercaseExtension(file) != ".avi")
    throw Error(file.string() + ": the view is recorded as Motion-JPEG in an AVI: name it .avi");
  const std::filesystem::path folder = file.has_parent_path() ? file.parent_path() : ".";
  std::error_code error;
  if (!std::filesystem::is_directory(folder, error))
    throw Error(file.string() + ": cannot record the view: no folder " + folder.string());
  if (std::filesystem::is_directory(file, error))
    throw Error(file.string() + ": cannot record the view: a folder has that name");
  impl_->file = file;
  impl_->partial = partialVideoPath(file);
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
  if (!r.writer.isOpened()) {
    // Opened with the first image, whose size the video keeps. OpenCV's own MJPEG writer (no
    // FFmpeg): the same on every machine.
    r.writer.open(r.partial.string(), cv::CAP_OPENCV_MJPEG,
                  cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), r.fps, cv::Size(width, height));
    if (!r.writer.isOpened())
      throw Error(r.file.string() + ": cannot write the view's video there");
    r.width = width;
    r.height = height;
  }
  const cv::Mat image(height, width, CV_8UC4, const_cast<uint8_t*>(rgba.data()));
  cv::cvtColor(image, r.bgr, cv::COLOR_RGBA2BGR);
  const cv::Mat* frame = &r.bgr;
  if (width != r.width || height != r.height) {
    cv::resize(r.bgr, r.scaled, cv::Size(r.width, r.height), 0, 0, cv::INTER_AREA);
    frame = &r.scaled;
  }
  // The frames skipped since the last one hold the last image (the new one when too long a gap).
  const int64_t skipped = r.last_id >= 0 ? frame_id - r.last_id - 1 : 0;
  if (skipped > 0 && skipped <= r.max_gap) {
    for (int64_t k = 0; k < skipped; ++k) {
      r.writer.write(r.last);
      ++r.written;
    }
  }
  r.writer.write(*frame);
  frame->copyTo(r.last);
  ++r.written;
  r.last_id = frame_id;
  // OpenCV's writer drops write errors: the disk's room is watched instead.
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
  if (!r.writer.isOpened()) return true;  // nothing recorded: no file
  r.writer.release();
  r.error = finishPartialVideo(r.partial, r.file, r.written, cv::CAP_OPENCV_MJPEG);
  if (!r.error.empty()) r.error += "; what was written is kept as " + r.partial.string();
  return r.error.empty();
}

const std::string& ViewRecorder::error() const {
  return impl_->error;
}

const std::filesystem::path& ViewRecorder::file() const {
  return impl_->file;
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
