#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/sim/studio_config.h"

namespace lumistage {

// What a drawn stage may be. The defaults are the randomised corpus's (docs/virtual-studio.md,
// "The randomised corpus").
struct StageDrawOptions {
  int min_cameras = 6;
  int max_cameras = 16;
  int frames = 60;  // the session's length: where the motion may start, how far it may roam
  double fps = 30;
  // The motions it draws from: the built-in clips (every one of builtinClipNames() unless limited
  // here) and these BVH files.
  std::vector<std::string> clips;  // empty: all the built-in clips
  std::vector<std::filesystem::path> bvh_files;
  // The motion starts at a random time of its clip, so mostly not in the T-pose the built-in clips
  // open with; false: at the clip's start.
  bool any_start = true;
};

// A whole virtual stage drawn from `seed`, the same one for the same seed and options on every
// machine (its own generator, not <random>'s distributions):
//   the rig: 6 to 16 cameras (options), a ring at 1 to 3 heights or an irregular circle, 3.2 to
//     4.5 m from the centre, 0.5 to 3 m high, 1280x720 to 1280x1024, each aimed near the centre
//     with the focal length that just fits a column 1 m in radius and 2.5 m tall (so every camera
//     sees the actor anywhere the motion takes him), principal points up to 14 px off centre,
//     barrel or pincushion distortion, cameras dealt to nodes of 1 to 4;
//   the actor: 1.50 to 2.05 m, limbs, shoulders and hips +-7 to 15 %, girth 0.9 to 1.35, belly 0.9
//     to 1.6, clothed four times in five;
//   the motion: a built-in clip or a BVH file, from a random time (any pose), its mean floor
//     position centred, turned to any heading and moved off-centre as far as it stays within
//     0.8 m of the centre;
//   the look: the screen's colour, unevenness and spill, the sensor's noise, RGB or a Bayer layout.
// The rig's stage box is 3 x 3 x 2.6 m about the centre. Throws Error when no motion can be drawn
// (a BVH file that does not read, a clip shorter than the session).
StudioConfig drawStage(uint32_t seed, const StageDrawOptions& options = {});

// The BVH files (.bvh, any case) directly in `folder`, sorted: what StageDrawOptions::bvh_files
// draws from for `lumistage corpus --motions`. Throws Error naming the folder when it is none or
// cannot be read.
std::vector<std::filesystem::path> bvhFilesIn(const std::filesystem::path& folder);

// One line: cameras and layout, size, actor, motion, look.
std::string describeStage(const StudioConfig& config);

}  // namespace lumistage
