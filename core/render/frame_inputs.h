#pragma once

#include <cstdint>
#include <vector>

#include "core/capture/frame_source.h"
#include "core/imaging/keyer.h"
#include "core/pipeline/silhouettes.h"
#include "core/render/lumigraph_renderer.h"

namespace lumistage {

// A single-process renderer's inputs for a frame of a session (leave-one-out, `lumistage render`):
// every camera's image and its foreground mask, as the nodes give theirs — the camera's
// silhouette keyed in kMaskStep-pixel cells by a green-screen keyer that learns the screen from
// the first frame given. Buffers are reused.
class FrameInputs {
 public:
  // `frames` indexed by the renderer's own cameras (all of the rig's, in order).
  void set(LumigraphRenderer& renderer, const std::vector<CameraFrame>& frames);

 private:
  std::vector<GreenScreenKeyer> keyers_;
  LowResSilhouette silhouette_;
  std::vector<uint8_t> mask_;
};

}  // namespace lumistage
