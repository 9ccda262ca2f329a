#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/capture/frame_source.h"
#include "core/capture/session_reader.h"

namespace lumistage {

enum class ReplayMode {
  kRecordedRate,      // each set when its timestamp is due, from the first call to next()
  kAsFastAsPossible,  // decoded from disk as they are asked for
  kFromMemory,        // all decoded up front, then served without disk or decoding (benchmarks)
};

struct ReplayOptions {
  ReplayMode mode = ReplayMode::kAsFastAsPossible;
  // Start again after the last set. Frame ids and timestamps go on increasing across loops (by
  // the session's span), so that consumers grouping or pacing by them see a longer recording.
  bool loop = false;
  // kFromMemory refuses (Error) a session whose decoded images would need more than this.
  size_t memory_limit_bytes = size_t(2) << 30;
  // Only these rig cameras (a camera node replays its own); empty: all of them.
  std::vector<int> cameras;
  // A session with masks of the actor (masks/, another tool's): every frame carries its mask
  // (CameraFrame::mask), read with its image; false: the images only.
  bool masks = true;
  // Paced by the machine's monotonic clock instead of from the first call: the set shown at time
  // t is number floor(t / period) (looping), stamped with that tick as frame id and tick x period
  // as timestamp. Every process replaying the session on a machine then shows the same frame at
  // the same instant with the same id, as hardware-triggered cameras do; with kFromMemory it
  // replays synchronised from memory. Implies looping.
  bool synchronized = false;
  // kFromMemory decodes the whole session when made (seconds for a dozen cameras): set this, from
  // another thread, to stop it; the constructor then throws Error.
  const std::atomic<bool>* cancel = nullptr;
};

// Replays a recorded session through the FrameSource interface: the frames of a set come out
// camera by camera (rig order), then the next set's. Frames are exactly what was recorded.
class SessionSource : public FrameSource {
 public:
  // Opens the session (SessionReader: throws Error) and, for kFromMemory, decodes it all.
  explicit SessionSource(const std::filesystem::path& folder, ReplayOptions options = {});

  const Rig& rig() const override { return reader_.rig(); }
  // False on timeout (kRecordedRate: the next set is not due yet), at the end, or for a set whose
  // image cannot be decoded (a file damaged since the session was opened): that set is skipped,
  // said once with its file, counted as dropped for every camera, and replay goes on
  // (stats().last_error says which file). Only when every set in a row fails does it finish, with
  // failure() saying why. With masks, a camera whose mask cannot be read skips that frame alone:
  // said once with its file, counted as dropped for that camera, and replay goes on.
  bool next(CameraFrame& frame, std::chrono::milliseconds timeout) override {
    return next(frame, timeout, true);
  }
  // The same, leaving `frame.image` as it was unless `with_image`: for a reader that wants a few
  // of the images only (the studio's previews: copying every frame of a 12-camera session from
  // memory took 0.08 of a core for previews of 4 a second). The frame's camera, id and time, and
  // the camera's counts, are as next()'s.
  bool next(CameraFrame& frame, std::chrono::milliseconds timeout, bool with_image);
  // The camera whose frame the next call delivers.
  int nextCamera() const { return cameras_[next_camera_]; }
  bool finished() const override { return finished_; }
  std::string failure() const override { return failure_; }
  bool idsCountInstants() const override { return false; }
  CameraStats stats(int camera) const override;
  bool hasMasks(int camera) const override;
  // The session's plate/ frames of the camera (SessionReader::readPlate); a file that cannot be
  // read is left out, warned of by name.
  std::vector<Image> plateImages(int camera) override;

  const SessionReader& reader() const { return reader_; }

 private:
  bool loadSet();     // into set_, for set index next_set_; false (the set skipped) when it fails
  void advanceSet();  // to the set after next_set_ (the end, or the first again when looping)

  SessionReader reader_;
  ReplayOptions options_;
  std::vector<std::vector<CameraFrame>> memory_;  // kFromMemory: every set
  std::vector<CameraFrame> set_;                  // the set being served (disk modes)
  int next_set_ = 0;                              // index of the set to serve next
  std::vector<int> cameras_;                      // rig cameras served, in order
  int next_camera_ =
      0;  // index into cameras_ of the one to serve next; 0: the set is not loaded yet
  int64_t loop_ = 0;
  int64_t tick_ = -1;                       // synchronized: the tick of the set being served
  int64_t id_span_ = 0, time_span_ns_ = 0;  // how much ids and timestamps advance per loop
  bool started_ = false;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_;
  std::vector<int64_t> delivered_;
  // synchronized: ticks passed without being served (a consumer too slow), which every camera
  // missed, as a slow reader of real cameras misses frames: their stats() count them dropped.
  int64_t skipped_ = 0;
  std::chrono::steady_clock::time_point first_delivery_, last_delivery_;
  std::string error_;
  std::string failure_;
  // Sets skipped as their images failed to decode: in all (each camera's dropped), in a row, and
  // for each set whether it was said (once per set, not once per loop).
  int64_t damaged_ = 0, damaged_in_a_row_ = 0;
  std::vector<uint8_t> damage_told_;
  std::vector<std::string> memory_errors_;  // kFromMemory: each set's decoding error, if any
  // With masks: why each rig camera's mask of the set being served could not be read (empty: it
  // was), kFromMemory every set's; frames lost to them per camera, and for each set and camera
  // whether it was said.
  bool masks_ = false;
  std::vector<std::string> mask_errors_;
  std::vector<std::vector<std::string>> memory_mask_errors_;
  std::vector<int64_t> mask_dropped_;
  std::vector<uint8_t> mask_told_;
  const std::vector<std::string>& maskErrors() const {
    return options_.mode == ReplayMode::kFromMemory ? memory_mask_errors_[next_set_] : mask_errors_;
  }
  // Whether camera c's frame of the set being served has no mask (said once, counted dropped).
  bool maskFailed(int c);
};

}  // namespace lumistage
