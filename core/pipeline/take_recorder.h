#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <list>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "core/base/output_path.h"
#include "core/capture/frame_source.h"
#include "core/capture/image_files.h"
#include "core/geometry/rig.h"
#include "core/net/message_codec.h"

namespace lumistage {

class SessionRecorder;

// A camera node's recording of takes, as the studio asks for them (RecordData): the node's own
// cameras' complete frame sets with ids in [first_frame, last_frame], written on the node's PC to
// <folder>/<take>/<node>/, a session of the node's cameras (docs/session-format.md) that
// `lumistage session merge` joins with the other nodes' parts into the take of the whole rig.
// Nothing of the frames crosses the network: twelve 1024x768 cameras at 25 frames a second are
// 236 MB/s of raw pixels, more than a studio's link takes.
//
// Capture never waits for the disk: sets go through a SessionRecorder (a bounded queue a second
// of sets deep and its own writer thread; a full queue drops the set and counts it), and a
// closed take finishes writing its queue on a thread of its own. A write error (disk full) stops
// that take with the error, and its part stays a valid session up to its last complete set.
class TakeRecorder {
 public:
  // `folder` empty: the node records nothing, and a take asked of it says so in its status.
  // `fps`: the cameras' frame rate, written in each part's session.yaml. `files`: how the images
  // are stored; PNM keeps up with the cameras where PNG's encoding may not (image_files.h).
  TakeRecorder(std::filesystem::path folder, const Rig& rig, std::string node, double fps,
               ImageFiles files = ImageFiles::kPnm);
  ~TakeRecorder();  // writes what is queued of the open take, then closes it
  TakeRecorder(const TakeRecorder&) = delete;
  TakeRecorder& operator=(const TakeRecorder&) = delete;

  // The studio's command (any thread). The same take again moves its frame range (the stop);
  // another take closes the open one; an empty take closes it and asks for none.
  void command(const RecordData& record);
  // Closes the open take (if any) for `why`, which its status then carries as its error.
  void abandon(const std::string& why);
  // A complete set of the node's cameras, in the node's camera order (the capture thread's):
  // queued when the take asks for its frame. Copies the images into buffers of sets already
  // written, so it allocates only while warming up. Sets come in increasing frame ids (a
  // session's index needs them so).
  void offer(int64_t frame_id, std::span<const CameraFrame* const> frames);
  // Whether a take asks for this frame (any thread).
  bool wants(int64_t frame_id) const;
  // For heartbeats (any thread). With the free space of the takes' disk, asked at most once a
  // second (the monitor window asks at its frame rate).
  TakeStatusData status() const;

 private:
  void close();  // under mutex_: the open take stops taking sets and drains on a thread of its own
  void open(int64_t frame_id, const CameraFrame& first);  // under mutex_

  const std::filesystem::path folder_;
  const Rig rig_;  // the node's cameras only, and the node
  const std::string node_;
  const double fps_;
  const ImageFiles files_;

  mutable std::mutex mutex_;
  RecordData wanted_;      // the studio's latest command
  TakeStatusData status_;  // take, error; frames from wanted_, counts from counted_
  std::unique_ptr<SessionRecorder> recorder_;  // the open take's
  std::vector<Image> images_;                  // the set being queued, reused
  const SessionRecorder* counted_ = nullptr;   // the recorder of status_.take (open or closing)
  int64_t first_timestamp_ns_ = 0;
  // The takes' disk and its free space, and when they were asked (under disk_mutex_).
  DiskSpace diskSpace() const;
  mutable std::mutex disk_mutex_;
  mutable DiskSpace disk_;
  mutable std::chrono::steady_clock::time_point disk_asked_{};
  // The take's ids that never reached offer() (their sets lost before: a camera that delivered
  // nothing, a capture that fell behind and missed the frames, a command heard late), counted
  // with the dropped ones: ids below next_id_ were offered or counted.
  int64_t next_id_ = 0;
  int64_t missed_ = 0;
  void countMissed(int64_t until);  // under mutex_: ids from next_id_ to `until` (excluded)
  bool closed_ = true;              // the take in status_ takes no more sets (none asked for yet)
  bool told_failed_ = false;        // said in the node's log that the take's writing failed

  // The closed takes still writing their queues out, each on a thread of its own: closing one
  // never waits for another (a take stopped while the one before still drains would otherwise
  // hold the capture thread, in offer(), and the heartbeat, in status(), until that disk is
  // done). Those done are let go at the next close.
  struct Closing {
    std::unique_ptr<SessionRecorder> recorder;
    std::atomic<bool> done{false};
    std::thread thread;
  };
  std::list<Closing> closing_;  // under mutex_; a list, so that each thread's entry stays put
};

}  // namespace lumistage
