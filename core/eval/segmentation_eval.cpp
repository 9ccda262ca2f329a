#include "core/eval/segmentation_eval.h"

#include <algorithm>
#include <cmath>

#include "core/imaging/clean_plate.h"
#include "core/imaging/keyer.h"

namespace lumistage {

SegmentationScore evaluateSegmentation(const SessionReader& session, const std::vector<int>& frames,
                                       const CameraPlates* given_plates) {
  const int n = session.rig().cameraCount();
  SegmentationScore score;
  if (session.frameCount() == 0 || n == 0) return score;
  std::vector<CameraFrame> images;
  std::vector<GreenScreenKeyer> keyers(n);
  session.readFrame(0, images);
  const CameraPlates plates = platesOf(session, given_plates);
  for (int c = 0; c < n; ++c) {
    score.threshold += keyers[c].learnScreen(images[c].image.view()) / double(n);
    const int excess = keyers[c].screenExcess();
    score.dimmest_screen = c == 0 ? excess : std::min(score.dimmest_screen, excess);
  }
  size_t actor = 0, missed = 0, extra = 0;
  for (int i : frames) {
    session.readFrame(i, images);
    for (int c = 0; c < n; ++c) {
      const std::vector<uint8_t> truth = session.readTruthMask(c, i);
      const ImageView image = images[c].image.view();
      for (int y = 0; y < image.height; ++y) {
        for (int x = 0; x < image.width; ++x) {
          const bool on_actor = truth[size_t(y) * image.width + x] != 0;
          const bool keyed = plates[c] ? plates[c]->isForeground(image, x, y)
                                       : keyers[c].isForeground(image, x, y);
          actor += on_actor;
          missed += on_actor && !keyed;
          extra += !on_actor && keyed;
        }
      }
    }
    ++score.frames;
  }
  if (actor > 0) {
    score.missed_pct = 100.0 * double(missed) / double(actor);
    score.extra_pct = 100.0 * double(extra) / double(actor);
  } else {
    score.missed_pct = score.extra_pct = std::nan("");  // no actor in the frames: not measured
  }
  return score;
}

}  // namespace lumistage
