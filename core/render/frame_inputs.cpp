#include "core/render/frame_inputs.h"

namespace lumistage {

void FrameInputs::set(LumigraphRenderer& renderer, const std::vector<CameraFrame>& frames) {
  const bool learn = keyers_.size() != frames.size();
  if (learn) keyers_.assign(frames.size(), GreenScreenKeyer());
  for (size_t c = 0; c < frames.size(); ++c) {
    const ImageView image = frames[c].image.view();
    renderer.setImage(static_cast<int>(c), image);
    if (learn) keyers_[c].learnScreen(image);
    computeSilhouette(keyers_[c], image, static_cast<int>(c), kMaskStep, silhouette_);
    silhouetteMask(silhouette_, mask_);
    renderer.setMask(static_cast<int>(c), mask_, silhouette_.width, silhouette_.height);
  }
}

}  // namespace lumistage
