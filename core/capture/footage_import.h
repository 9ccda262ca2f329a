#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/geometry/rig.h"

namespace lumistage {

// One camera's footage: a video file (anything FFmpeg reads: mp4, mkv, avi, mov) or a folder of
// images (png, jpg, ppm, pgm, bmp, tif; in name order), and how many frames it runs behind the
// others: the session's frame k takes its frame first + k * every + offset.
struct FootageSource {
  std::string camera;  // the rig's name for it
  std::filesystem::path path;
  int offset = 0;
};

struct FootageImportOptions {
  int first = 0;   // the footage's first frame taken (before offsets)
  int frames = 0;  // at most this many session frames; 0: as many as every camera has
  int every = 1;   // every n-th frame
  double fps = 0;  // the footage's rate; 0: the first video's own (image folders need it)
  // Another tool's masks of the actor, masks/<camera>/<footage frame, 6 digits>.png (non-zero on
  // the actor, the footage's size), copied into the session (docs/session-format.md): only the
  // frames every camera has a mask of are taken. Empty: none.
  std::filesystem::path masks;
};

struct FootageImportReport {
  int frames = 0;                  // session frames written
  int without_masks = 0;           // frames left out for a camera's missing mask
  int before_footage = 0;          // frames left out before a camera's footage begins
  Rig rig;                         // as written: image sizes the footage's where they differ
  std::vector<std::string> notes;  // size adjustments, where each camera's footage ended
};

// `camera` as footage of `width` x `height` pixels shows it: itself at its calibrated size; a few
// pixels smaller (up to 16: a video encoded 1080 wide for a 1088 sensor), the calibrated image
// cropped at its right and bottom edges, its intrinsics kept, with `note` saying so (else empty).
// Throws Error naming `file` for footage larger, smaller by more, or turned a quarter.
Camera cameraForFootage(const Camera& camera, int width, int height,
                        const std::filesystem::path& file, std::string& note);

// Writes a session (docs/session-format.md, RGB images, source "import") of `rig`'s cameras from
// their footage, one source for every camera of the rig. Each camera's frames are decoded in order
// (no seeking: every frame is counted, so offsets are frame-exact). Footage a few pixels smaller
// than its calibration (a video encoded 1080 wide for a 1088 sensor) is taken as the calibrated
// image cropped at its right and bottom edges: the camera keeps its intrinsics, its size becomes
// the footage's, and a note says so; footage larger, or smaller by more than 16 pixels, or turned,
// is refused. The session ends with the shortest footage, which a note names. `progress(done,
// total)` after each frame (total as the footage's containers announce). Throws Error naming the
// file or camera.
FootageImportReport importFootage(const Rig& rig, const std::vector<FootageSource>& sources,
                                  const std::filesystem::path& out,
                                  const FootageImportOptions& options,
                                  const std::function<void(int, int)>& progress = {});

}  // namespace lumistage
