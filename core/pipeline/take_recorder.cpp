#include "core/pipeline/take_recorder.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/base/output_path.h"
#include "core/capture/session_reader.h"
#include "core/capture/session_recorder.h"

namespace lumistage {

TakeRecorder::TakeRecorder(std::filesystem::path folder, const Rig& rig, std::string node,
                           double fps, ImageFiles files)
    : folder_(std::move(folder)),
      rig_(nodeRig(rig, node)),
      node_(std::move(node)),
      fps_(fps),
      files_(files) {}

TakeRecorder::~TakeRecorder() {
  {
    std::lock_guard lock(mutex_);
    close();
  }
  for (Closing& c : closing_) c.thread.join();
}

void TakeRecorder::close() {
  closed_ = true;
  if (!recorder_) return;
  // Takes closed before and written out by now: their threads have ended, joined at once. The
  // take whose figures the status shows stays.
  std::erase_if(closing_, [this](Closing& c) {
    if (!c.done || c.recorder.get() == counted_) return false;
    c.thread.join();
    return true;
  });
  Closing& c = closing_.emplace_back();
  c.recorder = std::move(recorder_);
  c.thread = std::thread([&c] {
    c.recorder->stop();
    c.done = true;
  });
}

void TakeRecorder::command(const RecordData& record) {
  std::lock_guard lock(mutex_);
  if (!record.take.empty() && record.take == wanted_.take &&
      record.first_frame != wanted_.first_frame) {
    // Another take under the same name (the studio restarted and offered its first name again):
    // written into this one's part it would join it in the merge, so nothing is written and the
    // studio hears why.
    close();
    counted_ = nullptr;
    status_ = {};
    status_.take = record.take;
    status_.error = fmt::format(
        "a take named {} was recorded already from frame {}: this one (from frame {}) needs "
        "another name",
        record.take, wanted_.first_frame, record.first_frame);
    spdlog::error("node {}: {}", node_, status_.error);
  } else if (record.take != wanted_.take) {
    close();
    counted_ = nullptr;
    status_ = {};
    told_failed_ = false;
    next_id_ = record.first_frame;
    missed_ = 0;
    status_.take = record.take;
    closed_ = record.take.empty();
    if (!record.take.empty() && folder_.empty()) {
      status_.error = "this node records no takes: start it with --takes FOLDER";
      closed_ = true;
      spdlog::error("node {}: take {}: {}", node_, record.take, status_.error);
    }
  }
  wanted_ = record;
}

void TakeRecorder::abandon(const std::string& why) {
  std::lock_guard lock(mutex_);
  if (closed_) return;
  close();
  status_.error = why;
  spdlog::warn("node {}: take {}: {}", node_, wanted_.take, why);
}

void TakeRecorder::open(int64_t frame_id, const CameraFrame& first) {
  // A node restarted during the take (a crash, a power cut) finds its first part there, valid up
  // to its last complete set: the rest goes beside it, <node>-2, <node>-3..., and the merge
  // joins them.
  std::filesystem::path part = folder_ / wanted_.take / node_;
  std::error_code ec;
  for (int k = 2; k < 100 && std::filesystem::exists(part / "session.yaml", ec); ++k) {
    // The frames an earlier part holds were not missed by this one.
    try {
      const SessionReader earlier(part);
      if (earlier.frameCount() > 0)
        next_id_ = std::max(next_id_, earlier.frameId(earlier.frameCount() - 1) + 1);
    } catch (const Error&) {  // unreadable: its frames are counted as missed
    }
    part = folder_ / wanted_.take / (node_ + "-" + std::to_string(k));
  }
  // The take's first frame beside the node's parts (<node>.first_frame, which the merge passes
  // over): parts there of another take of the same name (the studio restarted and offered its
  // first name again) are not continued, which would join both takes in the merge.
  const std::filesystem::path marker = folder_ / wanted_.take / (node_ + ".first_frame");
  if (std::filesystem::exists(marker, ec)) {
    int64_t recorded = -1;
    std::ifstream(marker) >> recorded;
    if (recorded != wanted_.first_frame) {
      status_.error = fmt::format(
          "{}: a take named {} was recorded there already from frame {}: this one (from frame "
          "{}) needs another name",
          (folder_ / wanted_.take).string(), wanted_.take, recorded, wanted_.first_frame);
      closed_ = true;
      spdlog::error("node {}: {}", node_, status_.error);
      return;
    }
  }
  try {
    // A second of sets queued: a disk's hiccup loses nothing (the reference node: 70 MB).
    const int queue = std::max(8, static_cast<int>(std::ceil(fps_)));
    recorder_ = std::make_unique<SessionRecorder>(part, rig_, first.image.format, fps_,
                                                  "lumistage-node " + node_, queue, files_);
    counted_ = recorder_.get();
    if (!std::filesystem::exists(marker, ec))
      writeFileAtomically(marker, std::to_string(wanted_.first_frame) + "\n");
    first_timestamp_ns_ = first.timestamp_ns;
    spdlog::info("node {}: recording take {} from frame {} into {}", node_, wanted_.take, frame_id,
                 part.string());
  } catch (const Error& e) {
    status_.error = e.what();
    closed_ = true;
    spdlog::error("node {}: take {}: {}", node_, wanted_.take, status_.error);
  }
}

void TakeRecorder::countMissed(int64_t until) {
  if (until <= next_id_) return;
  missed_ += until - next_id_;
  next_id_ = until;
}

bool TakeRecorder::wants(int64_t frame_id) const {
  std::lock_guard lock(mutex_);
  return !wanted_.take.empty() && frame_id >= wanted_.first_frame && frame_id <= wanted_.last_frame;
}

void TakeRecorder::offer(int64_t frame_id, std::span<const CameraFrame* const> frames) {
  std::lock_guard lock(mutex_);
  if (closed_ || wanted_.take.empty() || frames.empty() || frame_id < wanted_.first_frame) return;
  if (frame_id > wanted_.last_frame) {
    countMissed(wanted_.last_frame + 1);
    close();
    spdlog::info("node {}: take {} closed after frame {}", node_, wanted_.take, wanted_.last_frame);
    return;
  }
  if (!recorder_) open(frame_id, *frames.front());
  if (!recorder_) return;
  countMissed(frame_id);
  next_id_ = std::max(next_id_, frame_id + 1);
  if (images_.empty()) recorder_->takeSpareImages(images_);  // a written set's buffers
  images_.resize(frames.size());
  for (size_t k = 0; k < frames.size(); ++k) images_[k] = frames[k]->image;  // reuses the buffers
  // Queued: moved from. Dropped (the queue is full): kept for the next set.
  if (recorder_->push(frame_id, frames.front()->timestamp_ns - first_timestamp_ns_,
                      std::move(images_))) {
    images_.clear();
    return;
  }
  // Refused: the queue is full, or the writing failed (a failed recorder refuses every set). The
  // failure is said here too, not only in the studio's health: the node's own log is where a
  // technician looks for its disk.
  if (!told_failed_) {
    const RecorderStats stats = recorder_->stats();
    if (stats.failed) {
      told_failed_ = true;
      spdlog::error("node {}: take {}: recording stopped: {} (the sets written before are kept)",
                    node_, wanted_.take, stats.last_error);
    }
  }
}

DiskSpace TakeRecorder::diskSpace() const {
  if (folder_.empty()) return {};
  std::lock_guard lock(disk_mutex_);
  const auto now = std::chrono::steady_clock::now();
  if (now - disk_asked_ >= std::chrono::seconds(1)) {
    disk_ = diskSpaceAt(folder_);
    disk_asked_ = now;
  }
  return disk_;
}

TakeStatusData TakeRecorder::status() const {
  // Asked outside mutex_: a slow disk (a network mount) never holds up the capture's offer().
  const DiskSpace disk = diskSpace();
  std::lock_guard lock(mutex_);
  TakeStatusData status = status_;
  status.first_frame = wanted_.first_frame;
  status.last_frame = wanted_.last_frame;
  if (counted_ != nullptr) {
    const RecorderStats stats = counted_->stats();
    status.written = stats.written;
    status.dropped = stats.dropped + stats.refused + missed_;
    status.bytes = stats.bytes;
    if (stats.failed) status.error = stats.last_error;
  }
  // Finished once nothing is left to write, this take's sets or a closed one's still draining.
  status.finished = closed_ && std::all_of(closing_.begin(), closing_.end(),
                                           [](const Closing& c) { return c.done.load(); });
  status.free_bytes = disk.free_bytes;
  status.disk = disk.disk;
  return status;
}

}  // namespace lumistage
