#include "core/capture/session_source.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <thread>

#include "core/base/error.h"

namespace lumistage {

namespace {

void copyImage(const CameraFrame& from, CameraFrame& to) {
  to.image.resize(from.image.format, from.image.width, from.image.height);  // keeps the buffer
  std::memcpy(to.image.pixels.data(), from.image.pixels.data(), from.image.pixels.size());
  to.mask.assign(from.mask.begin(), from.mask.end());  // keeps the buffer too
}

}  // namespace

SessionSource::SessionSource(const std::filesystem::path& folder, ReplayOptions options)
    : reader_(folder),
      options_(options),
      delivered_(reader_.rig().cameraCount(), 0),
      masks_(options.masks && reader_.hasMasks()),
      mask_errors_(reader_.rig().cameraCount()),
      mask_dropped_(reader_.rig().cameraCount(), 0) {
  for (int c : options_.cameras) {
    if (c < 0 || c >= reader_.rig().cameraCount()) {
      throw Error(fmt::format("{}: replay of camera index {}, but the rig has {} cameras",
                              folder.string(), c, reader_.rig().cameraCount()));
    }
  }
  cameras_ = options_.cameras;
  if (options_.synchronized) options_.loop = true;
  if (cameras_.empty()) {
    for (int c = 0; c < reader_.rig().cameraCount(); ++c) cameras_.push_back(c);
  }
  const int frames = reader_.frameCount();
  if (frames > 0) {
    id_span_ = reader_.frameId(frames - 1) - reader_.frameId(0) + 1;
    time_span_ns_ = reader_.timestampNs(frames - 1) - reader_.timestampNs(0) +
                    int64_t(std::llround(1e9 / reader_.fps()));
  }
  finished_ = frames == 0;
  if (options_.mode != ReplayMode::kFromMemory) return;
  const size_t set_bytes = size_t(reader_.rig().pixelsPerSet(cameras_)) *
                           (bytesPerPixel(reader_.pixelFormat()) + (masks_ ? 1 : 0));
  const size_t needed = set_bytes * size_t(frames);
  if (needed > options_.memory_limit_bytes) {
    throw Error(fmt::format(
        "{}: replaying from memory needs {:.1f} MiB ({} frames of {} cameras), over the limit of "
        "{:.1f} MiB; replay from disk, or raise ReplayOptions::memory_limit_bytes",
        folder.string(), needed / 1048576.0, frames, cameras_.size(),
        options_.memory_limit_bytes / 1048576.0));
  }
  memory_.resize(frames);
  memory_errors_.resize(frames);
  memory_mask_errors_.resize(frames);
  int damaged = 0;
  for (int i = 0; i < frames; ++i) {
    if (options_.cancel && options_.cancel->load())
      throw Error(folder.string() + ": replay stopped while its frames were being loaded");
    try {
      reader_.readFrame(i, memory_[i], cameras_);
      if (masks_) reader_.readMasks(i, memory_[i], memory_mask_errors_[i], cameras_);
      memory_mask_errors_[i].resize(reader_.rig().cameraCount());
    } catch (const Error& e) {
      // Served as a set that failed (loadSet), as from disk.
      memory_[i].clear();
      memory_errors_[i] = e.what();
      memory_mask_errors_[i].assign(reader_.rig().cameraCount(), std::string());
      ++damaged;
    }
  }
  if (damaged == frames) {
    throw Error(fmt::format("{}: no frame of the session can be decoded; the first: {}",
                            folder.string(), memory_errors_[0]));
  }
}

bool SessionSource::loadSet() {
  std::string error;
  if (options_.mode == ReplayMode::kFromMemory) {
    error = memory_errors_[next_set_];
  } else {
    try {
      reader_.readFrame(next_set_, set_, cameras_);
      if (masks_) reader_.readMasks(next_set_, set_, mask_errors_, cameras_);
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
  if (error.empty()) {
    damaged_in_a_row_ = 0;
    return true;
  }
  // A damaged image costs its set, not the replay: the node or the stream goes on with the next.
  error_ = error;
  ++damaged_;
  damage_told_.resize(reader_.frameCount(), 0);
  if (!damage_told_[next_set_]) {
    damage_told_[next_set_] = 1;
    spdlog::warn("replay: {}; frame {} skipped (counted as dropped), the replay goes on", error,
                 reader_.frameId(next_set_));
  }
  if (++damaged_in_a_row_ >= reader_.frameCount()) {
    failure_ = fmt::format(
        "replay stopped: none of the session's {} frames left can be decoded; "
        "the last: {}",
        reader_.frameCount(), error);
    finished_ = true;
    return false;
  }
  if (!options_.synchronized) advanceSet();  // synchronized: the next tick says which set
  return false;
}

void SessionSource::advanceSet() {
  if (++next_set_ == reader_.frameCount()) {
    next_set_ = 0;
    if (options_.loop)
      ++loop_;
    else
      finished_ = true;
  }
}

bool SessionSource::next(CameraFrame& frame, std::chrono::milliseconds timeout, bool with_image) {
  using Clock = std::chrono::steady_clock;
  if (finished_) return false;
  const Clock::time_point now = Clock::now();
  if (!started_) {
    started_ = true;
    start_ = now;
  }
  if (options_.synchronized && next_camera_ == 0) {
    // The current tick of the shared clock, or the next one when it was served already; a slow
    // consumer skips ticks, as a slow reader of a real camera misses frames.
    const int64_t period_ns = int64_t(std::llround(1e9 / reader_.fps()));
    const int64_t now_ns =
        std::chrono::duration_cast<std::chrono::nanoseconds>(now.time_since_epoch()).count();
    const int64_t tick = std::max(tick_ + 1, now_ns / period_ns);
    const int64_t due_ns = tick * period_ns;
    if (due_ns - now_ns > std::chrono::nanoseconds(timeout).count()) {
      std::this_thread::sleep_for(timeout);
      return false;
    }
    std::this_thread::sleep_until(Clock::time_point(std::chrono::nanoseconds(due_ns)));
    if (tick_ >= 0) skipped_ += tick - tick_ - 1;
    tick_ = tick;
    next_set_ = static_cast<int>(tick % reader_.frameCount());
  }
  const int64_t timestamp =
      options_.synchronized
          ? tick_ * int64_t(std::llround(1e9 / reader_.fps()))
          : reader_.timestampNs(next_set_) + loop_ * time_span_ns_;  // of the set to serve
  if (options_.mode == ReplayMode::kRecordedRate && !options_.synchronized && next_camera_ == 0) {
    const Clock::time_point due =
        start_ + std::chrono::nanoseconds(timestamp - reader_.timestampNs(0));
    if (due > now + timeout) {
      std::this_thread::sleep_for(timeout);
      return false;
    }
    std::this_thread::sleep_until(due);
  }
  if (next_camera_ == 0 && !loadSet()) return false;

  const int c = cameras_[next_camera_];
  if (masks_ && maskFailed(c)) {
    // This camera's frame goes without its mask: skipped, the set's other cameras served.
    if (++next_camera_ == static_cast<int>(cameras_.size())) {
      next_camera_ = 0;
      advanceSet();
    }
    return false;
  }
  frame.camera = c;
  if (with_image && options_.mode == ReplayMode::kFromMemory) {
    copyImage(memory_[next_set_][c], frame);
  } else if (with_image) {
    // Swapped, not copied: the caller's old buffer receives the next decode.
    std::swap(frame.image, set_[c].image);
    std::swap(frame.mask, set_[c].mask);
  }
  frame.frame_id = options_.synchronized ? tick_ : reader_.frameId(next_set_) + loop_ * id_span_;
  frame.timestamp_ns = timestamp;

  const Clock::time_point delivered = Clock::now();
  if (delivered_[c]++ == 0 && next_camera_ == 0) first_delivery_ = delivered;
  last_delivery_ = delivered;
  if (++next_camera_ == static_cast<int>(cameras_.size())) {
    next_camera_ = 0;
    advanceSet();
  }
  return true;
}

bool SessionSource::hasMasks(int camera) const {
  return masks_ && std::find(cameras_.begin(), cameras_.end(), camera) != cameras_.end();
}

std::vector<Image> SessionSource::plateImages(int camera) {
  std::vector<Image> plate;
  const int frames = reader_.plateFrames(camera);
  for (int i = 0; i < frames; ++i) {
    try {
      plate.push_back(reader_.readPlate(camera, i));
    } catch (const Error& e) {
      spdlog::warn("{}: left out of the camera's plate", e.what());
    }
  }
  return plate;
}

bool SessionSource::maskFailed(int c) {
  const std::string& error = maskErrors()[c];
  if (error.empty()) return false;
  ++mask_dropped_[c];
  error_ = error;
  const size_t told = size_t(next_set_) * reader_.rig().cameraCount() + c;
  mask_told_.resize(size_t(reader_.frameCount()) * reader_.rig().cameraCount(), 0);
  if (!mask_told_[told]) {
    mask_told_[told] = 1;
    spdlog::warn(
        "replay: {}; camera {}'s frame {} skipped (counted as dropped), the replay goes on", error,
        reader_.rig().camera(c).name(), reader_.frameId(next_set_));
  }
  return true;
}

CameraStats SessionSource::stats(int camera) const {
  CameraStats stats;
  stats.frames = delivered_.at(camera);
  if (std::find(cameras_.begin(), cameras_.end(), camera) != cameras_.end())
    stats.dropped = skipped_ + damaged_ + mask_dropped_[camera];
  const double seconds = std::chrono::duration<double>(last_delivery_ - first_delivery_).count();
  stats.frame_rate_hz = stats.frames > 1 && seconds > 0 ? (stats.frames - 1) / seconds : 0.0;
  stats.temperature_c = std::nan("");  // a recording has no sensor
  stats.last_error = error_;
  return stats;
}

}  // namespace lumistage
