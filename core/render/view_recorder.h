#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>

namespace lumistage {

// Where a video is made until it is whole: NAME.partial.EXT beside NAME.EXT.
std::filesystem::path partialVideoPath(const std::filesystem::path& file);
// Puts the closed video `partial` in `file`'s place if it reads back `frames` frames (through
// OpenCV's reader `api`, 0: any); otherwise leaves both as they are. Empty when done, else why,
// naming `file` (the caller says what became of the partial file).
std::string finishPartialVideo(const std::filesystem::path& partial,
                               const std::filesystem::path& file, int64_t frames, int api = 0);

// Records a stream of the studio's blended images (one virtual camera) to a video as they are
// made: every frame the pipeline finishes, not the few a second a window shows. Motion-JPEG in an
// AVI, OpenCV's own encoder (nothing to install; 2.2 ms a 640x480 frame, render_bench), at the
// cameras' rate: frame ids the pipeline skipped (refused on arrival, lost) repeat the image before
// them, so that the video plays in real time; a gap longer than `max_gap_frames` is not filled (a
// paused source), and a frame older than the last one written is left out, unless it is
// kFrameIdWindow or more older (the cameras restarted: the recording goes on from it). Images of
// another size than the first are scaled to it. The video is written beside its name
// (`NAME.partial.avi`) and put in its place when closed, once it reads back whole: a full disk or a
// crash never leaves a torn video under the name, nor replaces an older one with it (the partial
// file is kept, and error() says why). Not thread-safe; add() reuses its conversion buffers.
class ViewRecorder {
 public:
  // Throws Error naming the file when it cannot be written (no folder, no rights, not .avi).
  ViewRecorder(const std::filesystem::path& file, double fps, int max_gap_frames = 30);
  ~ViewRecorder();  // finishes the file (close())
  ViewRecorder(const ViewRecorder&) = delete;
  ViewRecorder& operator=(const ViewRecorder&) = delete;

  // One blended image: RGBA8, rows top first (alpha is dropped: empty pixels are black). False,
  // writing nothing, when it is older than the last frame written or its size is 0. Throws Error
  // when the disk holds less than kMinFreeBytes (checked every kFreeCheckFrames frames): the
  // recording should stop there, what it holds is kept by close().
  bool add(int64_t frame_id, int width, int height, std::span<const uint8_t> rgba);
  // Writes the index, closes the file and puts it in its place if it reads back whole; later
  // add() calls write nothing. False (error() says why) when it does not.
  bool close();
  const std::string& error() const;  // empty while all is well

  static constexpr int64_t kMinFreeBytes = 64 << 20;
  static constexpr int kFreeCheckFrames = 30;

  const std::filesystem::path& file() const;
  int64_t framesWritten() const;  // repeats included
  double fps() const;
  int width() const;  // of the video (the first image's); 0 before it
  int height() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lumistage
