#pragma once

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
  void set(int x, int y) {
    const size_t i = size_t(y) * width + x;
    bits[i / 8] |= uint8_t(1u << (i % 8));
  }
};

// Keys every cell by the pixels around its centre (keyCell: only those are read) and packs the
// result. `out`'s buffer is reused.
void computeSilhouette(const GreenScreenKeyer& key, const ImageView& image, int camera, int step,
                       LowResSilhouette& out);

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
