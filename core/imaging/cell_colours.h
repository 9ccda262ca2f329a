#pragma once

#include <cstdint>
#include <vector>

#include "core/capture/image.h"
#include "core/imaging/silhouettes.h"

namespace lumistage {

// The actor's colours at a silhouette's resolution: each cell's mean RGB, for the cells the
// silhouette holds (the others zero). What motion capture's appearance term reads: a few bytes
// a cell of the actor, read only where the silhouette says the actor is.
// How often a node sends them: every this many frames (by frame id), with that frame's
// silhouettes. Motion capture needs them only when it has just found the actor, and takes the
// next frame that has them. On the reference rig, about 1000 cells of the actor a camera: 2.3 KB a
// captured frame a node, its traffic 4 % more (1.61 -> 1.67 MB/s, `lumistage run`).
inline constexpr int kColourEveryFrames = 4;

struct CellColours {
  int camera = -1;
  int step = 4;
  int width = 0, height = 0;  // in cells, as the silhouette's
  std::vector<uint8_t> rgb;   // 3 a cell, row by row

  const uint8_t* at(int x, int y) const { return rgb.data() + 3 * (size_t(y) * width + x); }
};

// How many of the first `cells` bits of `bits` (`bytes` long, least significant bit first) are
// set: a silhouette's cells of the actor, its last byte's padding bits left out (a hostile
// sender's are no cells).
size_t countActorCells(const uint8_t* bits, size_t bytes, size_t cells);

// The colours of `silhouette`'s set cells, in its bits' order, three bytes (RGB) each: each cell's
// mean over the 2x2 Bayer cells (or pixels) that tile it, read from the camera's own pixels (RGB8,
// or Bayer in its 2x2 cells, never demosaiced as a whole). What a node sends with its silhouettes.
// `out` is reused.
void sampleSilhouetteColours(const ImageView& image, const LowResSilhouette& silhouette,
                             std::vector<uint8_t>& out);
// Those colours laid out on the silhouette's grid (`packed`: `count` bytes, three a set cell).
// False, `out` left empty, when their count is not the set cells'.
bool expandSilhouetteColours(const LowResSilhouette& silhouette, const uint8_t* packed,
                             size_t count, CellColours& out);
// The cells' colours of a silhouette keyed in `image`: sampled and laid out on its grid.
void sampleCellColours(const ImageView& image, const LowResSilhouette& silhouette,
                       CellColours& out);

}  // namespace lumistage
