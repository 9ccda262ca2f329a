#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>

#include "core/base/status.h"

namespace lumistage {

// Where a video is made until it is whole: NAME.partial.EXT beside NAME.EXT.
std::filesystem::path partialVideoPath(const std::filesystem::path& file);

// What recoverPartialVideo() made.
struct RecoveredVideo {
  int64_t frames = 0;     // whole frames, in the order recorded
  double fps = 0;         // as the video was recorded
  int64_t bytes_cut = 0;  // at the end, of a frame the crash cut short
};
// Makes a whole video `out` of a ViewRecorder's video that was never closed (the studio or the run
// was killed, crashed or lost its power while recording). Motion-JPEG AVI: every whole frame up
// to the first one the end of the file cuts or leaves unwritten, copied byte for byte, then the
// index and the headers' frame counts that closing writes. MP4 (fragmented, a fragment a second):
// its whole fragments' frames copied into a plain MP4 (bytes_cut 0: the fragment being made is
// lost). `partial` is left as it is; `out` is written beside its name and put in place whole.
// Throws Error naming the file and what is wrong (not such a video, no whole frame in it, `out`
// exists).
RecoveredVideo recoverPartialVideo(const std::filesystem::path& partial,
                                   const std::filesystem::path& out);
// Where recoverPartialVideo() should write `partial`'s video: NAME-recovered.avi beside it for
// NAME.partial.avi or NAME.partial-K.avi (.mp4 for .mp4), or NAME-recovered-2.avi (-3...) when
// that exists.
std::filesystem::path recoveredVideoPath(const std::filesystem::path& partial);
// Whether a video recovered from `partial` (NAME-recovered.avi, -2...) lies beside it, made after
// `partial` last changed.
bool wasRecovered(const std::filesystem::path& partial);
// Puts the closed video `partial` in `file`'s place if it reads back `frames` frames (every packet
// of its video stream read through libavformat, probeVideoFile); otherwise leaves both as they
// are. Fails saying why, naming `file` (the caller says what became of the partial file).
Status finishPartialVideo(const std::filesystem::path& partial, const std::filesystem::path& file,
                          int64_t frames);

// Records a stream of the studio's blended images (one virtual camera) to a video as they are
// made: every frame the pipeline finishes, not the few a second a window shows. By the file's
// name: .mp4, H.264 through FFmpeg (libx264's ultrafast preset, CRF 20; a fragmented MP4 with a
// key frame and a fragment a second, video_file.h), or .avi, Motion-JPEG, OpenCV's own encoder
// (nothing to install). Per 640x480 frame (render_bench recordView, docs/lumigraph.md): 1.8 ms of
// the calling thread as MP4, 2.4-3.6 ms as AVI. At the cameras' rate: frame ids the pipeline
// skipped (refused on arrival, lost) repeat the image before them, so that the video plays in real
// time; a gap longer than `max_gap_frames` is not filled (a paused source), and a frame older than
// the last one written is left out, unless it is kFrameIdWindow or more older (the cameras
// restarted: the recording goes on from it). Images of another size than the first are scaled to
// it; an MP4 of odd size loses its last column or row (4:2:0). The video is written beside its name
// (`NAME.partial.avi`) and put in its place when closed, once it reads back whole: a full disk or a
// crash never leaves a torn video under the name, nor replaces an older one with it (the partial
// file is kept, and error() says why). A partial file left by a recording that never closed (a
// crash) is never written over: the recording goes to NAME.partial-2.avi (-3...) beside it, and
// leftover() names it for recoverPartialVideo(). Not thread-safe; add() reuses its conversion
// buffers.
class ViewRecorder {
 public:
  // Throws Error naming the file when it cannot be written (no folder, no rights, not .mp4 or
  // .avi).
  ViewRecorder(const std::filesystem::path& file, double fps, int max_gap_frames = 30);
  ~ViewRecorder();  // finishes the file (close())
  ViewRecorder(const ViewRecorder&) = delete;
  ViewRecorder& operator=(const ViewRecorder&) = delete;

  // One blended image: RGBA8, rows top first (alpha is dropped: empty pixels are black). False,
  // writing nothing, when it is older than the last frame written or its size is 0. Throws Error
  // when the disk holds less than kMinFreeBytes (checked every kFreeCheckFrames frames) or, for
  // an MP4, a write fails: the recording should stop there, what it holds is kept by close().
  bool add(int64_t frame_id, int width, int height, std::span<const uint8_t> rgba);
  // Writes the index, closes the file and puts it in its place if it reads back whole; later
  // add() calls write nothing. False (status() says why) when it does not.
  bool close();
  Status status() const;  // of close()

  static constexpr int64_t kMinFreeBytes = 64 << 20;
  static constexpr int kFreeCheckFrames = 30;

  const std::filesystem::path& file() const;
  // Where the video is written until it is closed and put in file()'s place (NAME.partial.avi,
  // or NAME.partial-K.avi beside a leftover one).
  const std::filesystem::path& partialFile() const;
  // A partial file of the name left by a recording that never closed; empty when none. And that in
  // words for the user, with how to recover it; empty when none.
  const std::filesystem::path& leftover() const;
  std::string leftoverNotice() const;
  int64_t framesWritten() const;  // repeats included
  double fps() const;
  int width() const;  // of the video (the first image's); 0 before it
  int height() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lumistage
