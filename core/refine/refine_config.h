#pragma once

#include <algorithm>
#include <cmath>
#include <string_view>

namespace YAML {
class Node;
}

namespace lumistage {

class YamlReader;

// The mesh refinement's parameters (the paper's §IV), read from the `refine:` section of a studio
// config (docs/virtual-studio.md documents every key). Each vertex of the posed generic mesh is
// tried at `offset_count` offsets uniformly in [-t_inward_m, t_max_m] along its normal; each offset
// gets an error, a weighted sum of terms (all terms are dimensionless, so the weights compare):
//   outside_weight  x cameras whose silhouette the point falls outside of (the visual hull term:
//                     0 on or inside the hull);
//   outward_weight  x -t / t_max: favours large outward offsets, i.e. points near the hull, at
//                     the vertices some camera sees on its contour (below), where the hull
//                     touches the surface; off_contour_outward_weight at the others, where it is
//                     only a bound on it;
//   colour_weight   x s²/(s² + colour_sigma²), s the colour standard deviation (8-bit levels)
//                     across the cameras that see the point (visibility from low-res depth
//                     maps); 1 when the point is outside the hull, unseen_colour when fewer than
//                     two cameras see it;
//   smooth_weight   x mean over neighbours of ((t - t_neighbour) / t_max)² (the weight in
//                     proportion to the mesh's vertices: smoothWeightFor()), and
//   temporal_weight x ((t - t_previous_frame) / t_max)²: beyond the paper, against ragged
//                     surfaces and shimmer on a still actor;
//   contour_weight  x -1 at a vertex's last sample inside the hull, where a camera sees the vertex
//                     on its silhouette's contour (RefinementStatistics::contour): the visual hull
//                     touches the surface along each camera's contour, so there the hull's crossing
//                     is the surface, elsewhere only a bound on it (beyond the paper);
// then the paper's fourth term: among the local minima within tie_margin of the lowest, the one
// closest to t = 0. The chosen surface is sent as a *level* on a grid of kLevelsPerStep levels a
// step (offsetLevels() of them): the offset of the chosen sample; where the next sample lies
// outside the hull, the silhouettes' edge between the two, located below a pixel by the nodes
// (RefinementStatistics::edges; halfway when none was located); or half a step toward the lowest
// point of the error's parabola through the sample and its neighbours.
struct RefineConfig {
  // The range: [-t_inward_m, t_max_m] along the normal (outward positive), offset_count samples
  // 5 mm apart by default. t_max_m also scales the outward, smoothness and temporal terms
  // (t / t_max_m). It reaches further out than in: a clothed actor is thicker than the generic
  // human (on the reference clips the best offsets' median is +21 mm), and the five samples
  // from -50 to -30 mm decided nothing that leave-one-out could tell (docs/lumigraph.md), for a
  // sixth of the nodes' samples and statistics.
  int offset_count = 18;
  double t_max_m = 0.05;
  double t_inward_m = 0.035;
  double outside_weight = 1.0;
  // 0.75 since the colour window: with a colour term that can be trusted further inside the hull,
  // a weaker pull toward it (docs/lumigraph.md).
  double outward_weight = 0.75;
  // The outward term at the vertices no camera sees on its contour (contour_cos, contour_probe_m):
  // between the legs, under the arms, on the loose shirt, where the hull is looser than the actor
  // and faint cloth left the outward term to carry the vertices past the surface (a quarter of
  // them more than 2 mm outside their best offset). 0.5 against 0.75: leave-one-camera-out on the
  // four reference clips (docs/lumigraph.md); 0.4 since the colours are despilled (`despill`),
  // which no longer holds the rim a step inside the actor.
  double off_contour_outward_weight = 0.4;
  double colour_weight = 1.0;
  double colour_sigma = 20.0;  // 8-bit levels
  double unseen_colour = 0.6;
  // 2 since the colours are despilled (1.5 before): leave-one-camera-out on the four reference
  // clips +0.01 dB over the mask, +0.03 matte, +0.06 strict matte (docs/lumigraph.md).
  double smooth_weight = 2.0;
  // The smoothness's weight follows the mesh's density: smooth_weight holds for a mesh of this
  // many vertices (the standard generic human's), a mesh of n vertices takes smooth_weight x n /
  // smooth_reference_vertices (smoothWeightFor()). A body's surface is the same whatever its
  // tessellation, so its edges are shorter by the square root of the ratio, a given slope of the
  // offsets makes differences between neighbours shorter by as much, and the term squares them.
  // The fine body (4054 vertices) so takes 4.2: leave-one-camera-out on the four reference clips,
  // eight frames a clip, +0.04 dB over the mask, +0.08 matte, +0.15 strict matte against 2
  // (docs/lumigraph.md). 0: smooth_weight for any mesh.
  int smooth_reference_vertices = 1930;
  double temporal_weight = 1.0;
  double tie_margin = 0.05;
  int smooth_iterations = 3;
  // Visibility: low-resolution depth maps of the posed mesh, 1/depth_map_step of the image in
  // each direction; a point is seen by a camera when it faces it (cosine above min_facing_cos) and
  // lies no further than depth_tolerance_m behind the depth map.
  int depth_map_step = 8;
  double depth_tolerance_m = 0.03;
  double min_facing_cos = 0.1;
  // Visibility from the refined surface (beyond the paper): where the nodes hold the refinement's
  // offsets of an earlier frame (the studio sends every frame's for the render), the depth maps,
  // the visibility tests and the contour marks are made on the posed mesh moved by them, a few
  // millimetres from the actor instead of two centimetres, and a point may then lie no further
  // than refined_depth_tolerance_m behind the map (depth_tolerance_m on the posed mesh alone, the
  // first frames). Leave-one-camera-out on the four reference clips +0.07 dB over the mask, +0.09
  // over the matte (docs/lumigraph.md).
  double refined_depth_tolerance_m = 0.015;
  int colour_bits = 6;  // colours are summed at this many bits a channel (<= 8)
  // Colour consistency over a small window of the surface (beyond the paper): with 3 points, each
  // vertex is also sampled at two points window_m to either side of it on its tangent plane,
  // along the tangent nearest the world's vertical (windowDirection()), at every offset, and a
  // sample's colour term is the mean over the three points inside the hull and seen by two
  // cameras or more. A single point matches the cameras on one pixel each, which uniform cloth and
  // the horizontal stripes of a shirt leave ambiguous along the normal (a ring of cameras moves
  // its projection sideways). 1 or 3; three times the nodes' samples and statistics.
  int window_points = 3;
  double window_m = 0.01;
  // A point's colour is read between pixels from the pixels (Bayer cells) around its projection
  // that the key holds well inside the actor: their background level (green excess) under
  // colour_purity of the key's bound (GreenScreenKeyer::isPureForegroundLevel); where none is,
  // from those keyed as the actor. A pixel the screen covers in part keys as the actor up to the
  // bound, its colour mixed with the screen's, and a Bayer cell on a silhouette's edge mixes its
  // channels from both sides: such colours made the rim's points look inconsistent and pulled
  // vertices inside the actor. Leave-one-camera-out on Bayer sessions of the four reference
  // clips +0.4 dB over the actor's mask, +0.2 dB matte; RGB the same (docs/lumigraph.md). In
  // (0, 1]; 1: every pixel keyed as the actor.
  double colour_purity = 0.4;
  // A green-screen camera's colours with their green limited to the larger of their red and blue
  // (the renderer's despill, docs/lumigraph.md): the screen's light spills green on the actor's
  // edges in the cameras that see them at a grazing angle and not in the others, and the colours
  // agreed best a step inside the actor, where a grazing camera's ray meets the surface more
  // squarely; the rim's vertices were drawn in (on the arms, +0.26 dB of leave-one-out where the
  // best offsets were put in their place). No effect on a learnt background's cameras.
  bool despill = true;
  // The contour term (beyond the paper). The visual hull touches the actor along each camera's
  // contour generator: where a camera sees a vertex edge-on with nothing behind it, the hull's
  // crossing along the normal is the surface; elsewhere (between the legs, under the arms) it is
  // only a bound. A vertex counts as on a camera's contour when the camera sees it (its depth map)
  // at a facing cosine in (0, contour_cos] and its point contour_probe_m out along its normal
  // falls where the posed mesh does not cover the depth map. Leave-one-camera-out on the four
  // reference clips +0.15 dB over the actor's mask and +0.06 dB over the matte (docs/lumigraph.md),
  // where a bonus at every vertex's hull crossing bought the mask's score with the matte's.
  double contour_weight = 0.05;
  double contour_cos = 0.3;
  double contour_probe_m = 0.015;
  static constexpr int kWindowPoints = 3;  // a vertex and its two window points
  // The points sampled for each vertex: 1, or kWindowPoints with the window (the statistics hold
  // this many times the vertices).
  int pointsPerVertex() const { return window_points == kWindowPoints ? kWindowPoints : 1; }
  // Whether the nodes mark the vertices on their cameras' contours (RefinementStatistics::contour):
  // the contour term or the outward term's split needs them.
  bool marksContours() const {
    return contour_weight > 0 || off_contour_outward_weight != outward_weight;
  }

  // The smoothness's weight for a mesh of `vertices` vertices (smooth_reference_vertices).
  double smoothWeightFor(int vertices) const {
    return smooth_reference_vertices > 0 ? smooth_weight * vertices / smooth_reference_vertices
                                         : smooth_weight;
  }

  double offsetAt(int index) const {
    return offset_count > 1 ? -t_inward_m + (t_inward_m + t_max_m) * index / (offset_count - 1)
                            : 0.0;
  }
  // The offset nearest 0 (the posed mesh itself).
  int zeroOffsetIndex() const {
    const double range = t_inward_m + t_max_m;
    if (offset_count < 2 || !(range > 0)) return offset_count / 2;
    return std::clamp(int(std::lround(t_inward_m / range * (offset_count - 1))), 0,
                      offset_count - 1);
  }
  // Levels: eighths of a step (0.625 mm by default), level kLevelsPerStep·i is offset index i; at
  // most 255 levels in a byte, hence at most kMaxOffsetCount offsets.
  static constexpr int kLevelsPerStep = 8;
  static constexpr int kMaxOffsetCount = 254 / kLevelsPerStep + 1;
  int offsetLevels() const { return kLevelsPerStep * (offset_count - 1) + 1; }
  double levelOffset(int level) const {
    return offset_count > 1 ? -t_inward_m + (t_inward_m + t_max_m) * level /
                                                (kLevelsPerStep * (offset_count - 1))
                            : 0.0;
  }
  int zeroLevel() const { return kLevelsPerStep * zeroOffsetIndex(); }
};

// Reads a `refine:` map over the defaults; every key optional, unknown keys and out-of-range values
// are Errors naming file:line: refine.key. `key` is the map's dotted path ("refine").
RefineConfig readRefineConfig(const YamlReader& in, const YAML::Node& node, std::string_view key);

}  // namespace lumistage
