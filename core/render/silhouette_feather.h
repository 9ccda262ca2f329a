#pragma once

#include <cstdint>
#include <span>

namespace lumistage {

// The view's silhouette feathered by one pixel, as the studio shows every view (docs/lumigraph.md,
// "Studio blend"). Rasterised at pixel centres, the mesh's silhouette is binary, and a few
// millimetres of geometry put it a pixel inside or outside the actor's. An empty pixel beside the
// silhouette (alpha 0, one or more of its 8 neighbours opaque) is given its opaque neighbours' mean
// colour at the probability that the actor covers it, which the count of those neighbours tells:
// measured on the virtual studio's reference clips, 1.5% beside a convex corner (1 neighbour), 8%
// along a straight edge (3), 27% at a step (4), 45% in a notch (5 or 6), a whole pixel in a hole
// (8). Premultiplied (over black): alpha = that probability, RGB = alpha x the colour, so that a
// video or an image without alpha shows the view over black, and a compositor blends it over its
// own background. The expected error of such a pixel is p(1 - p) of a colour's square instead of p
// empty or 1 - p drawn opaque: both the actor's mask and the matte score better
// (docs/lumigraph.md).
//
// rgba: width*height RGBA8, opaque pixels (alpha 255) the view's, every other pixel empty (its
// alpha 0; the pixels the feather writes are never opaque, so it may run again). row_begin and
// row_end, when given (height entries each), bound every row's opaque pixels to [begin, end) so
// that only the rows' spans and their neighbours are walked.
void featherSilhouette(std::span<uint8_t> rgba, int width, int height,
                       std::span<const int> row_begin = {}, std::span<const int> row_end = {});

// What the single-process renderer gives (alpha: the cameras' share of the weight, 0 where
// nothing was drawn) made what the studio's blend gives: every drawn pixel opaque, then feathered.
void finishSingleProcessView(std::span<uint8_t> rgba, int width, int height);

}  // namespace lumistage
