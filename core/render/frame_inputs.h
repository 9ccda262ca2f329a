#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "core/capture/frame_source.h"
#include "core/imaging/keyer.h"
#include "core/imaging/silhouettes.h"
#include "core/render/lumigraph_renderer.h"

namespace lumistage {

// Keys `image`'s silhouette in kMaskStep-pixel cells and gives it to `renderer` as own camera
// `own_index`'s foreground mask (what a node does for each of its cameras every frame).
// `silhouette` and `mask` are scratch buffers, reused.
void setForegroundMask(LumigraphRenderer& renderer, int own_index, const GreenScreenKeyer& keyer,
                       const ImageView& image, LowResSilhouette& silhouette,
                       std::vector<uint8_t>& mask);
// The same keyed on the camera's clean plate.
void setForegroundMask(LumigraphRenderer& renderer, int own_index, const BackgroundModel& plate,
                       const ImageView& image, LowResSilhouette& silhouette,
                       std::vector<uint8_t>& mask);
// The same from the frame's mask of the actor (another tool's: one byte a pixel, non-zero on the
// actor, `width` x `height`).
void setForegroundMask(LumigraphRenderer& renderer, int own_index,
                       const std::vector<uint8_t>& actor_mask, int width, int height,
                       LowResSilhouette& silhouette, std::vector<uint8_t>& mask);

// A single-process renderer's inputs for a frame of a session (leave-one-out, `lumistage render`):
// every camera's image and its foreground mask, as the nodes give theirs — the camera's
// silhouette keyed in kMaskStep-pixel cells by a green-screen keyer that learns the screen from
// the first frame given, or taken from the frame's mask where it carries one (CameraFrame::mask).
// Buffers are reused.
class FrameInputs {
 public:
  // `frames` indexed by the renderer's own cameras (all of the rig's, in order).
  void set(LumigraphRenderer& renderer, const std::vector<CameraFrame>& frames);
  // Each rig camera's clean plate (sessionPlates), which keys it instead of its green screen where
  // one is; none: every camera on green.
  void setPlates(CameraPlates plates) { plates_ = std::move(plates); }

 private:
  CameraPlates plates_;
  std::vector<GreenScreenKeyer> keyers_;
  LowResSilhouette silhouette_;
  std::vector<uint8_t> mask_;
};

}  // namespace lumistage
