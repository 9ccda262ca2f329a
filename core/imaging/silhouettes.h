#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/capture/image.h"
#include "core/imaging/keyer.h"

namespace lumistage {

// A camera's silhouette at low resolution, one bit a cell of step x step pixels (1: the actor),
// cell i = y * width + x in bit i % 8 of byte i / 8: the wire format of SilhouetteMaskData, so it
// crosses the network without repacking. What a node sends for motion capture: 6 KB for
// a 1024x768 camera at step 4, against 786 KB for its Bayer image.
struct LowResSilhouette {
  int camera = -1;  // index in the rig
  int step = 8;
  int width = 0, height = 0;  // in cells
  std::vector<uint8_t> bits;

  bool at(int x, int y) const {
    const size_t i = size_t(y) * width + x;
    return (bits[i / 8] >> (i % 8)) & 1;
  }
  // Camera `camera`'s empty silhouette of an image of `width` x `height` pixels in cells of `step`
  // (its buffer reused).
  void reset(int camera_index, int cell_step, int image_width, int image_height) {
    camera = camera_index;
    step = cell_step;
    width = image_width / step;
    height = image_height / step;
    bits.assign((size_t(width) * height + 7) / 8, 0);
  }
  void set(int x, int y) {
    const size_t i = size_t(y) * width + x;
    bits[i / 8] |= uint8_t(1u << (i % 8));
  }
};

// Keys every cell by the pixels around its centre (keyCell: only those are read) and packs the
// result. `out`'s buffer is reused.
void computeSilhouette(const GreenScreenKeyer& key, const ImageView& image, int camera, int step,
                       LowResSilhouette& out);
// The same keyed on a clean plate (a stage that is not green): each cell by the pixel at its
// centre (the plate's bound is several times the sensor's noise; a 3x3 mean, which a green key
// needs, widened the silhouette by a pixel all round), its holes filled (fillHoles).
void computeSilhouette(const BackgroundModel& key, const ImageView& image, int camera, int step,
                       LowResSilhouette& out);
// Sets every cell that the silhouette encloses: the background cells no 4-connected path of
// background cells joins to the image's border. A room's colours are also the actor's (a white
// shirt's stripe before a white wall), and a hole keyed in one camera's silhouette carves a tunnel
// through the visual hull and pushes the bones out of it; a gap the actor encloses (hands on the
// hips) is filled too, and carved away by the cameras that see through it.
void fillHoles(LowResSilhouette& silhouette);
// The cells a silhouette's actor spans, gathered while keying it.
struct CellBox {
  int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
  void add(int x, int y) {
    x0 = std::min(x0, x), x1 = std::max(x1, x);
    y0 = std::min(y0, y), y1 = std::max(y1, y);
  }
};
// The same when the silhouette's actor lies within `box`.
void fillHoles(LowResSilhouette& silhouette, const CellBox& box);

// A mask (one byte a pixel, non-zero on the actor: another tool's) as the silhouette a node would
// key: a cell is set when the pixel at its centre is. `out`'s buffer is reused.
void maskSilhouette(const uint8_t* mask, int width, int height, int camera, int step,
                    LowResSilhouette& out);

// The silhouette as one byte a cell (255 foreground, 0 not): the lumigraph's foreground mask
// (LumigraphRenderer::setMask). `out` is reused.
void silhouetteMask(const LowResSilhouette& silhouette, std::vector<uint8_t>& out);
// The cell size of those masks, in pixels.
inline constexpr int kMaskStep = 4;

}  // namespace lumistage
