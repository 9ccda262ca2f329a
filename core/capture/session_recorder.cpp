#include "core/capture/session_recorder.h"

#include <fmt/format.h>

#include "core/base/error.h"

namespace lumistage {

SessionRecorder::SessionRecorder(const std::filesystem::path& folder, const Rig& rig,
                                 PixelFormat format, double fps, const std::string& source,
                                 int queue_capacity, ImageFiles files)
    : folder_(folder),
      rig_(rig),
      format_(format),
      capacity_(size_t(std::max(queue_capacity, 1))),
      writer_(std::make_unique<SessionWriter>(folder, rig, format, fps, source,
                                              std::vector<std::string>{}, files)) {
  thread_ = std::thread([this] { run(); });
}

SessionRecorder::~SessionRecorder() {
  stop();
}

bool SessionRecorder::push(int64_t frame_id, int64_t timestamp_ns, std::vector<Image>&& images) {
  // Checked here rather than by the writer: one bad set is dropped, the recording goes on.
  std::string wrong;
  if (images.size() != size_t(rig_.cameraCount())) {
    wrong = fmt::format("{}: frame {}: {} images for {} cameras; set dropped", folder_.string(),
                        frame_id, images.size(), rig_.cameraCount());
  }
  for (int c = 0; wrong.empty() && c < rig_.cameraCount(); ++c) {
    const Image& image = images[c];
    const Camera& camera = rig_.camera(c);
    if (image.format != format_ || image.width != camera.width() ||
        image.height != camera.height() || image.pixels.size() != image.view().bytes()) {
      wrong = fmt::format(
          "{}: frame {}, camera {}: a {}x{} {} image, the session holds {}x{} {}; "
          "set dropped",
          folder_.string(), frame_id, camera.name(), image.width, image.height,
          pixelFormatName(image.format), camera.width(), camera.height(), pixelFormatName(format_));
    }
  }
  std::lock_guard lock(mutex_);
  if (stopping_ || stats_.failed) {
    ++stats_.refused;
    return false;
  }
  if (!wrong.empty()) {
    ++stats_.dropped;
    stats_.last_error = std::move(wrong);
    return false;
  }
  if (queue_.size() >= capacity_) {
    ++stats_.dropped;
    return false;
  }
  queue_.push_back({frame_id, timestamp_ns, std::move(images)});
  wake_.notify_one();
  return true;
}

bool SessionRecorder::takeSpareImages(std::vector<Image>& images) {
  std::lock_guard lock(mutex_);
  if (spares_.empty()) return false;
  images = std::move(spares_.back());
  spares_.pop_back();
  return true;
}

void SessionRecorder::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_one();
  if (thread_.joinable()) thread_.join();
}

RecorderStats SessionRecorder::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

void SessionRecorder::run() {
  std::vector<ImageView> views;
  while (true) {
    Item item;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
      if (queue_.empty()) return;  // stopping, all written
      item = std::move(queue_.front());
      queue_.pop_front();
    }
    views.clear();
    for (const Image& image : item.images) views.push_back(image.view());
    std::string error;
    try {
      writer_->writeFrame(item.frame_id, item.timestamp_ns, views);
    } catch (const std::exception& e) {
      error = e.what();
    }
    std::lock_guard lock(mutex_);
    if (!error.empty()) {
      // The writer left the session valid (the set is not in the index): stop cleanly there.
      stats_.failed = true;
      stats_.last_error = std::move(error);
      stats_.dropped += int64_t(queue_.size()) + 1;
      queue_.clear();
      return;
    }
    stats_.written = writer_->framesWritten();
    stats_.bytes = writer_->bytesWritten();
    if (spares_.size() < capacity_ + 1) spares_.push_back(std::move(item.images));
  }
}

}  // namespace lumistage
