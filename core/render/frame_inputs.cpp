#include "core/render/frame_inputs.h"

namespace lumistage {

namespace {

template <typename Key>
void keyedMask(LumigraphRenderer& renderer, int own_index, const Key& key, const ImageView& image,
               LowResSilhouette& silhouette, std::vector<uint8_t>& mask) {
  computeSilhouette(key, image, own_index, kMaskStep, silhouette);
  silhouetteMask(silhouette, mask);
  renderer.setMask(own_index, mask, silhouette.width, silhouette.height);
}

}  // namespace

void setForegroundMask(LumigraphRenderer& renderer, int own_index, const GreenScreenKeyer& keyer,
                       const ImageView& image, LowResSilhouette& silhouette,
                       std::vector<uint8_t>& mask) {
  keyedMask(renderer, own_index, keyer, image, silhouette, mask);
}

void setForegroundMask(LumigraphRenderer& renderer, int own_index, const BackgroundModel& plate,
                       const ImageView& image, LowResSilhouette& silhouette,
                       std::vector<uint8_t>& mask) {
  keyedMask(renderer, own_index, plate, image, silhouette, mask);
}

void setForegroundMask(LumigraphRenderer& renderer, int own_index,
                       const std::vector<uint8_t>& actor_mask, int width, int height,
                       LowResSilhouette& silhouette, std::vector<uint8_t>& mask) {
  maskSilhouette(actor_mask.data(), width, height, own_index, kMaskStep, silhouette);
  silhouetteMask(silhouette, mask);
  renderer.setMask(own_index, mask, silhouette.width, silhouette.height);
}

void FrameInputs::set(LumigraphRenderer& renderer, const std::vector<CameraFrame>& frames) {
  const bool learn = keyers_.size() != frames.size();
  if (learn) keyers_.assign(frames.size(), GreenScreenKeyer());
  for (size_t c = 0; c < frames.size(); ++c) {
    const ImageView image = frames[c].image.view();
    renderer.setImage(static_cast<int>(c), image);
    if (learn) keyers_[c].learnScreen(image);
    if (!frames[c].mask.empty())
      setForegroundMask(renderer, static_cast<int>(c), frames[c].mask, image.width, image.height,
                        silhouette_, mask_);
    else if (c < plates_.size() && plates_[c])
      setForegroundMask(renderer, static_cast<int>(c), *plates_[c], image, silhouette_, mask_);
    else
      setForegroundMask(renderer, static_cast<int>(c), keyers_[c], image, silhouette_, mask_);
  }
}

}  // namespace lumistage
