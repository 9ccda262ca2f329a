#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/imaging/take_plate.h"

namespace lumistage {

struct MaskRepairOptions {
  TakePlateOptions plate;
  // Where to write pictures of the repairs to look at (repairPicture: CAMERA-FFFFFF.png, at most
  // 960 pixels on a side), every `picture_every`-th frame of each camera. Empty: none.
  std::filesystem::path pictures;
  int picture_every = 5;
};

// One camera's repair over the session's frames.
struct MaskRepairCamera {
  std::string camera;
  int frames = 0;           // masks repaired
  double known = 0;         // the share of its view where the plate is known
  double changed = 0;       // the mean over its frames of PlateRepair::changed() (1 - IoU)
  double most = 0;          // the largest of them
  int64_t most_frame = -1;  // in which frame (its id)
  // Pixels the repair added and removed over every frame, as shares of the given masks' pixels.
  double added = 0, removed = 0;
  // The share of the repaired masks' pixels taken from the given ones (the plate unknown there).
  double fallback = 0;
};

struct MaskRepairReport {
  std::vector<MaskRepairCamera> cameras;  // the rig's order
  int frames = 0;                         // the session's frames
  bool again = false;                     // the masks were repaired before (from masks-given/)
  std::vector<std::string> notes;         // frames without a given mask, and the like
};

// Repairs a session's masks (docs/session-format.md) with a clean plate of each camera learnt from
// the take itself (TakePlate): the given masks are kept untouched in masks-given/ (moved there from
// masks/ the first time; a session repaired before is repaired again from them), the repaired
// ones take their place in masks/, which every later step reads. The new masks are written to
// masks.repairing/ and put in place once all are whole: a repair cut short leaves the session as it
// was, or (between the two renames) masks-given/ without masks/, which a repair run again mends.
// A frame one camera has no given mask of keeps none (a note says so). Throws Error naming the
// folder or file: a session without masks, a mask of another size than its camera, a camera
// without a single mask. `progress(done, total)` over every camera's frames read.
MaskRepairReport repairSessionMasks(const std::filesystem::path& session,
                                    const MaskRepairOptions& options = {},
                                    const std::function<void(int, int)>& progress = {});

// The report as a table a person reads: per camera, the plate's known share of the view, how much
// of each mask changed (mean, most and where), the pixels added and removed, the share of the
// repaired masks taken from the given ones.
std::string describeMaskRepair(const MaskRepairReport& report);

}  // namespace lumistage
