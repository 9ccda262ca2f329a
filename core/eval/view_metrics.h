#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "core/capture/image.h"
#include "core/render/lumigraph_renderer.h"

namespace lumistage {

// How close a rendered view is to a camera's real image, over the actor's mask.
struct ViewScore {
  double psnr_db = 0;  // over R, G, B of the mask's pixels (peak 255)
  double ssim = 0;     // mean SSIM of luma (7x7 box windows, the usual constants) over the mask
  int64_t pixels = 0;  // in the mask
  // The view as it would be composited: both images over black (every pixel the render draws
  // opaque, as the studio's blend shows it; the real one through the mask), compared over every
  // pixel either covers, so that a pixel drawn beyond the actor costs as much as one of the actor
  // left undrawn.
  double matte_psnr_db = 0;
  double missed_pct = 0;  // the mask's pixels not drawn (alpha under 128), % of the mask
  double beyond_pct = 0;  // pixels drawn (alpha 128 or more) outside the mask, % of the mask
  // Of the squared error over the mask (psnr_db's), the share on the pixels left undrawn, %: a
  // pixel of the actor the render misses costs its whole colour (black against the actor), so a
  // silhouette a pixel too tight can outweigh the texture's misregistration inside it.
  double missed_error_pct = 0;
};

// `rendered` and `truth` RGBA8, `rendered` a view as the studio shows it, premultiplied (its colour
// is the view over black; psnr_db and ssim ignore alpha: a pixel the renderer left empty is black
// and counts as an error), `mask` one byte a pixel (non-zero: the actor), all width x height.
// An empty mask (no actor in the view) scores NaN over the mask, the matte over what was drawn.
ViewScore compareOverMask(std::span<const uint8_t> rendered, std::span<const uint8_t> truth,
                          std::span<const uint8_t> mask, int width, int height);

// Any camera image as RGBA8: Bayer demosaiced at full resolution (demosaicBayerToRgba, as a
// camera's software would show it), mono8 as grey.
void imageToRgba(const ImageView& image, std::vector<uint8_t>& rgba);

// Leave-one-camera-out: every camera's view rendered from the others (that camera inactive in the
// weights) and compared with its real image over its mask. `renderer` owns every camera of its
// rig, has their images and the mesh; `truth[c]` RGBA8 and `masks[c]` of camera c's size.
std::vector<ViewScore> leaveOneOut(LumigraphRenderer& renderer, const Rig& rig,
                                   const std::vector<std::vector<uint8_t>>& truth,
                                   const std::vector<std::vector<uint8_t>>& masks);
// The same for camera `left_out` alone; the view rendered into `rendered` when given. Views are
// scored as the studio shows them: opaque where drawn, the silhouette feathered
// (finishSingleProcessView).
ViewScore leaveOneOut(LumigraphRenderer& renderer, const Rig& rig,
                      const std::vector<std::vector<uint8_t>>& truth,
                      const std::vector<std::vector<uint8_t>>& masks, int left_out,
                      std::vector<uint8_t>* rendered = nullptr);

// A view beside the camera's image, for a person to see where it fails: three panels side by
// side, RGB8 (rows top first): the render over black, the camera's image, and the error map: over
// the actor's mask the mean absolute difference of the three channels, four times, in grey; red
// where the mask has the actor and the render drew nothing; blue where the render drew beyond the
// actor; black elsewhere. Each panel is the view cropped to the actor and what was drawn, with a
// margin of kPictureMargin pixels (all of it when there is neither). Inputs as compareOverMask
// takes them (throws Error for other sizes).
struct ComparisonPicture {
  static constexpr int kPictureMargin = 16;
  int width = 0, height = 0;  // of the three panels together
  std::vector<uint8_t> rgb;   // width * height * 3
};
void comparisonPicture(std::span<const uint8_t> rendered, std::span<const uint8_t> truth,
                       std::span<const uint8_t> mask, int width, int height,
                       ComparisonPicture& picture);

}  // namespace lumistage
