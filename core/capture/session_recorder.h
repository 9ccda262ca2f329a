#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/capture/image.h"
#include "core/capture/session_writer.h"
#include "core/geometry/rig.h"

namespace lumistage {

struct RecorderStats {
  int64_t written = 0;     // frame sets in index.csv
  int64_t dropped = 0;     // sets lost: queue full, wrong images, or queued when writing failed
  int64_t refused = 0;     // pushes after stop() or after a write error
  int64_t bytes = 0;       // PNG bytes of the written camera images
  bool failed = false;     // a write error stopped the recording
  std::string last_error;  // the write error (it names the file), or why a set was dropped
};

// Records frame sets to a session (SessionWriter) on its own thread, so that acquisition never
// waits for the disk: push() queues a set (a bounded queue) or drops it when the queue is full.
// A write error (disk full...) stops the recording: the error is kept, later pushes are refused,
// and the session on disk stays valid up to the last set in index.csv. Never throws after
// construction.
class SessionRecorder {
 public:
  // Creates the session as SessionWriter does (throws its Error) and starts the writer thread.
  SessionRecorder(const std::filesystem::path& folder, const Rig& rig, PixelFormat format,
                  double fps, const std::string& source, int queue_capacity = 8,
                  ImageFiles files = ImageFiles::kPng);
  ~SessionRecorder();  // stop()
  SessionRecorder(const SessionRecorder&) = delete;
  SessionRecorder& operator=(const SessionRecorder&) = delete;

  // Queues one set: per camera of the rig an image of its size in the session's format. False
  // (and counted) when the queue is full, the images do not fit, or the recording has stopped.
  // Never blocks on the disk; `images` is moved from only when the set is queued.
  bool push(int64_t frame_id, int64_t timestamp_ns, std::vector<Image>&& images);
  // Buffers of a written set to fill for the next push, so that recording allocates nothing once
  // warmed up. False when none is spare yet (allocate then).
  bool takeSpareImages(std::vector<Image>& images);

  // Writes what is queued, then ends the writer thread. Idempotent.
  void stop();
  RecorderStats stats() const;
  const std::filesystem::path& folder() const { return folder_; }

 private:
  struct Item {
    int64_t frame_id;
    int64_t timestamp_ns;
    std::vector<Image> images;
  };
  void run();

  std::filesystem::path folder_;
  Rig rig_;
  PixelFormat format_;
  size_t capacity_;
  std::unique_ptr<SessionWriter> writer_;

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Item> queue_;
  std::vector<std::vector<Image>> spares_;
  bool stopping_ = false;
  RecorderStats stats_;
  std::thread thread_;
};

}  // namespace lumistage
