#pragma once

#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "core/capture/image.h"

namespace lumistage {

// What a take's clean plate is learnt and keyed with. A handful of numbers, none tuned to one take.
struct TakePlateOptions {
  // At most this many frames are learnt from (spread over the take: TakePlate::framesToLearn), so
  // that a long take costs no more memory than a short one.
  int frames = 32;
  // The given masks grow by this many pixels before they say where the background shows: a
  // segmenter's edge is a few pixels off, and the actor's soft edge blurs the colour around it.
  int margin = 15;
  // A pixel's plate is known where at least `min_share` of the frames, and `min_frames`, leave it
  // free. The median is the background's while fewer than half of its samples show the actor: with
  // half the frames free, wherever the given masks miss the actor at a pixel in fewer than a
  // quarter of the frames. Where they leave it free in fewer, the actor most likely stood there in
  // those too (a torso the segmenter missed in a run of frames would become the plate).
  int min_frames = 3;
  double min_share = 0.5;
  // A pixel keys as the actor where its colour (5x5 blurred) is further from the plate's than this
  // many 8-bit levels in some channel (compression, flicker), and than `spread_k` times the
  // pixel's own spread over the frames it was learnt from (1.4826 x its median absolute deviation:
  // a monitor, a moving treadmill belt, leaves in the wind).
  int floor = 25;
  float spread_k = 4.0f;
  // A shadow: a pixel between `darkest_shadow` and 1 of the plate's brightness whose colour, the
  // plate's scaled to that brightness, is within `shadow_colour` of the pixel's threshold. It is
  // background: an actor's shadow on the floor is not his silhouette.
  float darkest_shadow = 0.4f;
  float shadow_colour = 0.5f;
  // Holes in the mask (background the actor encloses) smaller than this share of the image are
  // filled: the actor's own colour matching the plate's there (skin against a beige wall).
  double hole = 0.001;
  // Larger cameras are learnt and keyed scaled down to about this many pixels (a 1088x1920 camera
  // is not), their masks scaled back up: memory and time stay bounded for 4K cameras.
  int max_pixels = 2'200'000;
};

// One frame's repair (TakePlate::repair), in pixels of the camera's image.
struct PlateRepair {
  std::vector<uint8_t> mask;  // 255 on the actor, the camera's size
  size_t given = 0;           // the given mask's pixels
  size_t repaired = 0;        // the repaired mask's
  size_t added = 0;           // in the repaired mask, not in the given
  size_t removed = 0;         // in the given, not in the repaired
  size_t fallback = 0;        // repaired pixels taken from the given mask (the plate unknown there)
  // 1 - IoU of the given and repaired masks: 0 unchanged, 1 nothing in common.
  double changed() const {
    const size_t either = repaired + removed;
    return either == 0 ? 0.0 : double(added + removed) / double(either);
  }
};

// A camera's clean plate, learnt from a take of the actor guided by another tool's masks of him
// (a segmenter's, which may miss a limb or take in furniture): for each pixel, the per-channel
// median of its colour (5x5 blurred) over the frames whose given mask, grown by `margin`, leaves it
// free, and the spread of those colours. A frame is then keyed by its distance from the plate
// where the plate is known, and takes the given mask where it is not (pixels the actor covers in
// most frames: feet on a treadmill belt). Of the keyed pixels only the regions that touch the given
// mask or the plate's unknown part (where the actor stands most of the take), grown by `margin`,
// are kept, so that a bystander, or flicker far from the actor, is dropped, and an arm is kept
// that the given mask misses along with the torso it hangs from; small holes are filled.
//
// What it holds: while learning, each frame added blurred (3 bytes a pixel) and where it is free
// (1 byte), at the working size (at most max_pixels): for 32 frames of a 1088x1920 camera, 267 MB,
// released by learn(); after it, the plate, its per-pixel threshold and where it is known: 5 bytes
// a pixel (10 MB).
class TakePlate {
 public:
  // A plate of a camera of `width` x `height` pixels; `camera` names it in errors. Throws Error
  // for a size that is not positive or options out of range.
  TakePlate(std::string camera, int width, int height, const TakePlateOptions& options = {});

  // The frames of a take of `count` frames to learn from: all of them up to `cap`, else `cap`
  // of them evenly spread from the first to the last.
  static std::vector<int> framesToLearn(int count, int cap);

  // Adds a frame (RGB8, mono8 or Bayer, the camera's size) and its given mask (mono8, the camera's
  // size, non-zero on the actor). Throws Error naming the camera and both sizes for either of
  // another size, and for more frames than options.frames.
  void add(const ImageView& image, const ImageView& given);
  // Learns the plate from the frames added (from fewer than min_frames, it knows no pixel: every
  // mask stays as given). Throws Error naming the camera when none was added.
  void learn();
  bool learnt() const { return !plate_.empty(); }

  // Frame `image`'s repaired mask and how it differs from `given` (as add() takes them; after
  // learn(), else Error).
  PlateRepair repair(const ImageView& image, const ImageView& given) const;

  // The share of the camera's view where the plate is known.
  double knownShare() const;
  // At the working size (plate().size()): the plate (RGB, blurred), where it is known (255), each
  // pixel's threshold (8-bit levels).
  const cv::Mat& plate() const { return plate_; }
  const cv::Mat& known() const { return known_; }
  const cv::Mat& threshold() const { return threshold_; }
  const std::string& camera() const { return camera_; }

 private:
  // The image as RGB at the working size, 5x5 blurred; the mask as 0/255 at the working size.
  cv::Mat prepareImage(const ImageView& image) const;
  cv::Mat prepareMask(const ImageView& given) const;
  // Where the frame `blurred` differs from the plate beyond its threshold and is no shadow.
  cv::Mat key(const cv::Mat& blurred) const;
  // The keyed regions touching the given mask or the plate's unknown part, the given mask where
  // the plate is unknown, holes filled.
  cv::Mat clean(const cv::Mat& keyed, const cv::Mat& given) const;

  std::string camera_;
  int width_, height_;
  cv::Size work_;  // the working size
  TakePlateOptions options_;
  std::vector<cv::Mat> frames_, free_;  // while learning
  cv::Mat plate_, known_, threshold_;
};

// A picture of a repair to look at, RGB at the camera's size: the frame dimmed where both masks
// agree on the background, green where both say actor, red where only the repair does, blue where
// only the given mask does, purple stripes where the plate is unknown.
Image repairPicture(const TakePlate& plate, const ImageView& image, const ImageView& given,
                    const std::vector<uint8_t>& repaired);

}  // namespace lumistage
