#include "core/render/view_recorder.h"

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "core/base/error.h"

namespace lumistage {

struct ViewRecorder::Impl {
  std::filesystem::path file;
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
  if (file.extension() != ".avi")
    throw Error(file.string() + ": the view is recorded as Motion-JPEG in an AVI: name it .avi");
  const std::filesystem::path folder = file.has_parent_path() ? file.parent_path() : ".";
  std::error_code error;
  if (!std::filesystem::is_directory(folder, error))
    throw Error(file.string() + ": cannot record the view: no folder " + folder.string());
  impl_->file = file;
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
  if (r.last_id >= 0 && frame_id <= r.last_id) return false;
  if (!r.writer.isOpened()) {
    // Opened with the first image, whose size the video keeps. OpenCV's own MJPEG writer (no
    // FFmpeg): the same on every machine.
    r.writer.open(r.file.string(), cv::CAP_OPENCV_MJPEG,
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
  return true;
}

void ViewRecorder::close() {
  Impl& r = *impl_;
  if (r.closed) return;
  r.closed = true;
  if (r.writer.isOpened()) r.writer.release();
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
