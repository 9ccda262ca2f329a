#include "core/capture/footage_import.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "core/base/error.h"
#include "core/capture/session_writer.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

// The largest shortfall of footage against its calibration taken as a crop.
constexpr int kMaxCropPixels = 16;

bool isImage(const fs::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  for (const char* known : {".png", ".jpg", ".jpeg", ".ppm", ".pgm", ".bmp", ".tif", ".tiff"})
    if (ext == known) return true;
  return false;
}

// One camera's frames, in order.
class Footage {
 public:
  explicit Footage(const FootageSource& source) : source_(source) {
    std::error_code ec;
    if (fs::is_directory(source.path, ec)) {
      for (const fs::directory_entry& entry : fs::directory_iterator(source.path, ec))
        if (entry.is_regular_file() && isImage(entry.path())) images_.push_back(entry.path());
      if (ec) throw Error(source.path.string() + ": " + ec.message());
      std::sort(images_.begin(), images_.end());
      if (images_.empty()) throw Error(source.path.string() + ": no images in this folder");
      const cv::Mat first = cv::imread(images_[0].string(), cv::IMREAD_COLOR);
      if (first.empty()) throw Error(images_[0].string() + ": cannot read this image");
      width_ = first.cols, height_ = first.rows;
    } else {
      if (!fs::is_regular_file(source.path, ec))
        throw Error(source.path.string() + ": no such video file or image folder");
      video_ = std::make_unique<cv::VideoCapture>(source.path.string(), cv::CAP_FFMPEG);
      if (!video_->isOpened())
        throw Error(source.path.string() +
                    ": cannot open as a video (FFmpeg reads mp4, mkv, avi, "
                    "mov...)");
      width_ = int(video_->get(cv::CAP_PROP_FRAME_WIDTH));
      height_ = int(video_->get(cv::CAP_PROP_FRAME_HEIGHT));
      fps_ = video_->get(cv::CAP_PROP_FPS);
    }
  }

  int width() const { return width_; }
  int height() const { return height_; }
  double fps() const { return fps_; }  // 0 for images
  // Its frames: an image folder's, a video's as its container says (for the progress bar only:
  // the frames decoded decide).
  int count() const {
    return video_ ? std::max(0, int(video_->get(cv::CAP_PROP_FRAME_COUNT))) : int(images_.size());
  }
  bool isVideo() const { return video_ != nullptr; }

  // Frame `index` (never one before the last asked for) as BGR into `bgr`; false past the end.
  bool frame(int index, cv::Mat& bgr) {
    if (index < 0) return false;
    if (!video_) {
      if (size_t(index) >= images_.size()) return false;
      bgr = cv::imread(images_[size_t(index)].string(), cv::IMREAD_COLOR);
      if (bgr.empty()) throw Error(images_[size_t(index)].string() + ": cannot read this image");
      if (bgr.cols != width_ || bgr.rows != height_)
        throw Error(fmt::format("{}: {}x{}, the folder's first image is {}x{}",
                                images_[size_t(index)].string(), bgr.cols, bgr.rows, width_,
                                height_));
      return true;
    }
    while (next_ <= index) {
      if (!video_->read(bgr) || bgr.empty()) return false;
      ++next_;
    }
    return true;
  }

  const FootageSource& source() const { return source_; }

 private:
  FootageSource source_;
  std::vector<fs::path> images_;
  std::unique_ptr<cv::VideoCapture> video_;
  int next_ = 0;  // the video's next frame
  int width_ = 0, height_ = 0;
  double fps_ = 0;
};

}  // namespace

Camera cameraForFootage(const Camera& camera, int width, int height, const fs::path& file,
                        std::string& note) {
  note.clear();
  const int dw = camera.width() - width, dh = camera.height() - height;
  if (dw == 0 && dh == 0) return camera;
  if (dw < 0 || dh < 0 || dw > kMaxCropPixels || dh > kMaxCropPixels)
    throw Error(
        fmt::format("{}: {}x{} pixels, camera '{}' is calibrated at {}x{}{}", file.string(), width,
                    height, camera.name(), camera.width(), camera.height(),
                    width == camera.height() && height == camera.width()
                        ? ": the footage is turned a quarter (rotate it, or calibrate it as it is)"
                        : ": not this camera's footage, or another calibration"));
  note = fmt::format(
      "camera '{}': footage {}x{}, calibrated {}x{}: taken as the calibrated image cropped by {} "
      "px at the right and {} px at the bottom (intrinsics kept)",
      camera.name(), width, height, camera.width(), camera.height(), dw, dh);
  return Camera(camera.name(), width, height, camera.intrinsics(), camera.distortion(),
                camera.rotation(), camera.translation());
}

FootageImportReport importFootage(const Rig& rig, const std::vector<FootageSource>& sources,
                                  const fs::path& out, const FootageImportOptions& options,
                                  const std::function<void(int, int)>& progress) {
  if (options.every < 1 || options.first < 0 || options.frames < 0 || !(options.fps >= 0))
    throw Error("footage import: expected first >= 0, frames >= 0, every >= 1, fps >= 0");
  FootageImportReport report;
  // The footage in the rig's camera order.
  std::vector<std::unique_ptr<Footage>> footage(size_t(rig.cameraCount()));
  for (const FootageSource& source : sources) {
    const std::optional<int> c = rig.findCamera(source.camera);
    if (!c)
      throw Error(
          fmt::format("{}: the rig has no camera '{}'", source.path.string(), source.camera));
    if (footage[size_t(*c)])
      throw Error(fmt::format("camera '{}': given footage twice", source.camera));
    footage[size_t(*c)] = std::make_unique<Footage>(source);
  }
  std::vector<Camera> cameras;
  double fps = options.fps;
  for (int c = 0; c < rig.cameraCount(); ++c) {
    const Camera& camera = rig.camera(c);
    if (!footage[size_t(c)])
      throw Error(fmt::format("camera '{}': no footage given for it", camera.name()));
    const Footage& f = *footage[size_t(c)];
    if (fps <= 0 && f.fps() > 0) fps = f.fps();
    std::string note;
    cameras.push_back(cameraForFootage(camera, f.width(), f.height(), f.source().path, note));
    if (!note.empty()) report.notes.push_back(std::move(note));
  }
  if (!(fps > 0)) throw Error("footage import: image folders carry no frame rate: give one (fps)");
  report.rig = Rig(cameras, rig.nodes());
  report.rig.setStage(rig.stage());

  // The session's rate: every n-th frame of the footage's.
  SessionWriter writer(out, report.rig, PixelFormat::kRgb8, fps / options.every, "import");
  std::vector<cv::Mat> bgr(cameras.size()), rgb(cameras.size()), masks(cameras.size());
  std::vector<ImageView> views(cameras.size());
  const int last = options.frames > 0 ? options.frames : std::numeric_limits<int>::max();
  int expected = last;
  for (const auto& f : footage)
    expected =
        std::min(expected,
                 std::max(0, (f->count() - options.first - f->source().offset + options.every - 1) /
                                 options.every));
  for (int k = 0; k < last; ++k) {
    const int base = options.first + k * options.every;
    // A camera whose footage starts later (a negative offset) has no frame yet: skipped.
    bool before = false;
    for (const auto& f : footage) before = before || base + f->source().offset < 0;
    if (before) {
      ++report.before_footage;
      continue;
    }
    int ended = -1;
    for (size_t c = 0; c < cameras.size() && ended < 0; ++c) {
      const int index = base + footage[c]->source().offset;
      if (!footage[c]->frame(index, bgr[c])) ended = int(c);
    }
    if (ended >= 0) {
      const FootageSource& s = footage[size_t(ended)]->source();
      report.notes.push_back(fmt::format(
          "camera '{}': its footage ends before its frame {} (offset {}): the session ends there, "
          "after {} frames",
          s.camera, base + s.offset, s.offset, report.frames));
      break;
    }
    bool masked = true;
    for (size_t c = 0; c < cameras.size() && masked && !options.masks.empty(); ++c) {
      const fs::path file = options.masks / cameras[c].name() /
                            fmt::format("{:06}.png", base + footage[c]->source().offset);
      std::error_code ec;
      masked = fs::is_regular_file(file, ec);
      if (!masked) break;
      masks[c] = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
      if (masks[c].cols != cameras[c].width() || masks[c].rows != cameras[c].height())
        throw Error(fmt::format("{}: expected a {}x{} mask (camera '{}'), got {}", file.string(),
                                cameras[c].width(), cameras[c].height(), cameras[c].name(),
                                masks[c].empty()
                                    ? std::string("no image")
                                    : fmt::format("{}x{}", masks[c].cols, masks[c].rows)));
    }
    if (!masked) {
      ++report.without_masks;
      continue;
    }
    const int id = report.frames;
    for (size_t c = 0; c < cameras.size(); ++c) {
      cv::cvtColor(bgr[c], rgb[c], cv::COLOR_BGR2RGB);
      views[c] = {PixelFormat::kRgb8, rgb[c].cols, rgb[c].rows, rgb[c].data};
      if (options.masks.empty()) continue;
      // A frame's masks before its index line: a reader that sees the frame finds them.
      const fs::path folder = out / "masks" / cameras[c].name();
      fs::create_directories(folder);
      cv::Mat binary = masks[c] > 127;
      writePngAtomically(folder / fmt::format("{:06}.png", id),
                         {PixelFormat::kMono8, binary.cols, binary.rows, binary.data});
    }
    // Timestamps are the footage's time.
    writer.writeFrame(id, int64_t(std::llround(1e9 * (base - options.first) / fps)), views);
    report.frames = id + 1;
    if (progress) progress(k + 1, std::max(expected, k + 1));
  }
  if (report.before_footage > 0)
    report.notes.push_back(fmt::format(
        "{} frames left out at the start: a camera's footage (negative offset) begins later",
        report.before_footage));
  if (report.without_masks > 0)
    report.notes.push_back(
        fmt::format("{} frames left out: a camera has no mask of them", report.without_masks));
  if (report.frames == 0) throw Error("footage import: no frame that every camera has");
  return report;
}

}  // namespace lumistage
