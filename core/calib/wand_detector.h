#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/capture/image.h"

namespace lumistage {

// Finds the wand's bright point in a frame of the dark stage: the intensity-weighted centroid
// (sub-pixel) of the one blob of pixels above a threshold. Only bright pixels are touched after
// the scan: the scan tests each pixel against the threshold and gives up as soon as more pixels
// are bright than a wand point can cover (a light left on, a reflection). Two or more blobs are
// ambiguous and the frame is rejected for this camera, as MultiCamSelfCal does.
struct WandDetectorOptions {
  int threshold = 160;    // intensity (0..255) a pixel must exceed
  int min_pixels = 2;     // smaller blobs are noise (hot pixels)
  int max_pixels = 4000;  // more bright pixels than this in the frame: rejected
};

struct WandDetection {
  enum class Status { kFound, kNone, kAmbiguous, kTooBright };
  Status status = Status::kNone;
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();  // OpenCV convention: (0,0) centre of pixel 0
  int pixels = 0;                                   // of the blob
  int blobs = 0;
};

class WandDetector {
 public:
  explicit WandDetector(const WandDetectorOptions& options = {}) : options_(options) {}
  // Mono8 and Bayer frames use the raw values; rgb8 the brightest channel. Reuses its buffers:
  // no allocation once they have grown to a frame's bright pixel count.
  WandDetection detect(const ImageView& image);

 private:
  struct Bright {
    int x, y, weight;
  };
  WandDetectorOptions options_;
  std::vector<Bright> bright_;
  std::vector<int> label_;
  std::vector<int> stack_;
};

}  // namespace lumistage
