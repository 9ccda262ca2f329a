#include "core/refine/refinement_sampler.h"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "core/refine/mesh_refiner.h"

namespace lumistage {

namespace {

// The four pixels around a pixel position (u, w), pixel centres at integers, or on a Bayer image
// the four 2x2 cells (what the key and colourAt() read), clamped to the image, with the bilinear
// weights of the right and lower ones.
struct Neighbours {
  int x0, y0, x1, y1;  // pixel coordinates of a pixel, or of a cell's first pixel
  float fx, fy;
};

// A camera's image as the refinement interpolates it: its grid of pixels or Bayer cells, and on
// Bayer where a cell's red, greens and blue lie from its first pixel, worked out once a camera
// instead of at every read (the colour term reads five pixels a sample; the grid's size divided out
// at each read cost about 0.2 ms of a node's 7.5, near the bench's noise; colourAt's choice of
// format and layout at each read, a fifth of the sampler's instructions).
class PixelGrid {
 public:
  explicit PixelGrid(const ImageView& image)
      : image_(image),
        bayer_(isBayer(image.format)),
        step_(bayer_ ? 2 : 1),
        columns_(image.width / step_),
        rows_(image.height / step_) {
    if (!bayer_) return;
    const BayerLayout l = bayerLayout(image.format);
    const int w = image.width;
    red_ = l.red_y * w + l.red_x, blue_ = (1 - l.red_y) * w + 1 - l.red_x;
    green_red_row_ = l.red_y * w + 1 - l.red_x, green_blue_row_ = (1 - l.red_y) * w + l.red_x;
  }

  // colourAt() for a pixel inside the image (as the sampler's reads are).
  Rgb colour(int x, int y) const {
    if (!bayer_) return colourAt(image_, x, y);
    const int x0 = std::min(x, image_.width - 2) & ~1, y0 = std::min(y, image_.height - 2) & ~1;
    return cellColour(image_.data + size_t(y0) * size_t(image_.width) + size_t(x0));
  }
  // The colours of the four neighbours `n` (within the image), in the order (x0, y0), (x1, y0),
  // (x0, y1), (x1, y1).
  void colours(const Neighbours& n, Rgb out[4]) const {
    if (!bayer_) {
      out[0] = colourAt(image_, n.x0, n.y0), out[1] = colourAt(image_, n.x1, n.y0);
      out[2] = colourAt(image_, n.x0, n.y1), out[3] = colourAt(image_, n.x1, n.y1);
      return;
    }
    const size_t w = size_t(image_.width);
    const uint8_t *row0 = image_.data + size_t(n.y0) * w, *row1 = image_.data + size_t(n.y1) * w;
    out[0] = cellColour(row0 + n.x0), out[1] = cellColour(row0 + n.x1);
    out[2] = cellColour(row1 + n.x0), out[3] = cellColour(row1 + n.x1);
  }

  Neighbours around(float u, float w) const {
    // A Bayer cell k holds pixels 2k and 2k + 1: its centre is at 2k + 0.5.
    const float x = std::clamp(bayer_ ? (u - 0.5f) * 0.5f : u, 0.0f, float(columns_ - 1));
    const float y = std::clamp(bayer_ ? (w - 0.5f) * 0.5f : w, 0.0f, float(rows_ - 1));
    const int x0 = std::max(0, std::min(int(x), columns_ - 2)),
              y0 = std::max(0, std::min(int(y), rows_ - 2));
    const int x1 = std::min(x0 + 1, columns_ - 1), y1 = std::min(y0 + 1, rows_ - 1);
    return {x0 * step_, y0 * step_, x1 * step_, y1 * step_, x - float(x0), y - float(y0)};
  }

 private:
  Rgb cellColour(const uint8_t* cell) const {
    return {cell[red_], (cell[green_red_row_] + cell[green_blue_row_] + 1) / 2, cell[blue_]};
  }

  ImageView image_;
  bool bayer_;
  int step_, columns_, rows_;
  int red_ = 0, blue_ = 0, green_red_row_ = 0, green_blue_row_ = 0;
};

// The key's background levels (GreenScreenKeyer::backgroundLevel) of the four neighbours `n` of
// colours `c`.
template <typename Key>
void backgroundLevels(const Key& key, const Neighbours& n, const Rgb c[4], float levels[4]) {
  levels[0] = float(key.backgroundLevel(c[0], n.x0, n.y0));
  levels[1] = float(key.backgroundLevel(c[1], n.x1, n.y0));
  levels[2] = float(key.backgroundLevel(c[2], n.x0, n.y1));
  levels[3] = float(key.backgroundLevel(c[3], n.x1, n.y1));
}

// Bilinear between the four neighbours' levels.
float levelBetween(const Neighbours& n, const float levels[4]) {
  return (1 - n.fy) * ((1 - n.fx) * levels[0] + n.fx * levels[1]) +
         n.fy * ((1 - n.fx) * levels[2] + n.fx * levels[3]);
}

// The key's background level at pixel position (u, w), bilinear between the pixels around it.
template <typename Key>
float interpolatedBackgroundLevel(const Key& key, const PixelGrid& grid, float u, float w) {
  const Neighbours n = grid.around(u, w);
  Rgb c[4];
  grid.colours(n, c);
  float levels[4];
  backgroundLevels(key, n, c, levels);
  return levelBetween(n, levels);
}

// The bilinear weights in fixed point: a whole pixel weighs kWeightOne.
constexpr int kWeightBits = 6, kWeightOne = 1 << (2 * kWeightBits);

// The actor's colour at a point keyed as the actor, whose four neighbours `n` have colours `c`, on
// the statistics' scale (`shift` bits dropped): bilinear between the neighbours the key holds
// well inside the actor (RefineConfig::colour_purity), or where none is, between those keyed as
// the actor, their weights renormalised, so that the screen's colour beside a silhouette (and in
// the pixels it covers in part) does not make the rim's points look inconsistent; the nearest
// pixel's (ix, iy) where none is either (a clean plate whose pixels' bounds differ around
// the point). The nearest pixel alone put a point's projection up to half a pixel off in every
// camera, a colour error that the variance counts as inconsistency: leave-one-camera-out +0.25 to
// +0.37 dB (docs/lumigraph.md).
template <typename Key>
void interpolatedColour(const Key& key, const PixelGrid& grid, const Neighbours& n, const Rgb c[4],
                        const float levels[4], int ix, int iy, int shift, float purity,
                        uint32_t rgb[3]) {
  constexpr float kScale = float(1 << kWeightBits);
  const int wx = int(n.fx * kScale + 0.5f), wy = int(n.fy * kScale + 0.5f);
  constexpr int kOne = 1 << kWeightBits;
  const int xs[4] = {n.x0, n.x1, n.x0, n.x1}, ys[4] = {n.y0, n.y0, n.y1, n.y1};
  const int weights[4] = {(kOne - wx) * (kOne - wy), wx * (kOne - wy), (kOne - wx) * wy, wx * wy};
  bool counted[4], any_pure = false;
  for (int k = 0; k < 4; ++k) {
    counted[k] = key.isPureForegroundLevel(levels[k], xs[k], ys[k], purity);
    any_pure = any_pure || counted[k];
  }
  if (!any_pure)
    for (int k = 0; k < 4; ++k) counted[k] = key.isForegroundLevel(levels[k], xs[k], ys[k]);
  int sum = 0, r = 0, g = 0, b = 0;
  for (int k = 0; k < 4; ++k) {
    const int wk = counted[k] ? weights[k] : 0;
    sum += wk, r += wk * c[k].r, g += wk * c[k].g, b += wk * c[k].b;
  }
  if (sum == kWeightOne) {
    constexpr int kHalf = kWeightOne / 2, kBits = 2 * kWeightBits;
    rgb[0] = uint32_t((r + kHalf) >> kBits) >> shift;
    rgb[1] = uint32_t((g + kHalf) >> kBits) >> shift;
    rgb[2] = uint32_t((b + kHalf) >> kBits) >> shift;
  } else if (sum > 0) {
    rgb[0] = uint32_t((r + sum / 2) / sum) >> shift;
    rgb[1] = uint32_t((g + sum / 2) / sum) >> shift;
    rgb[2] = uint32_t((b + sum / 2) / sum) >> shift;
  } else {
    const Rgb nearest = grid.colour(ix, iy);
    rgb[0] = uint32_t(nearest.r) >> shift, rgb[1] = uint32_t(nearest.g) >> shift,
    rgb[2] = uint32_t(nearest.b) >> shift;
  }
}

// Where a camera's silhouette edge lies between the projections `a` (keyed actor) and `b` (keyed
// background) of two consecutive samples, below a pixel: the fraction of the way from a to b where
// the interpolated background level is halfway between the actor's and the background's (read a
// step further in and out: the pixels at a and b may be mixed), i.e. where the actor covers half a
// pixel. As an edge byte (RefinementStatistics::edges), 0 when the two sides do not differ.
template <typename Key>
uint8_t locateEdge(const Key& key, const PixelGrid& grid, const Eigen::Vector2f& a,
                   const Eigen::Vector2f& b) {
  const Eigen::Vector2f d = b - a;
  const auto level = [&](float f) {
    const Eigen::Vector2f p = a + f * d;
    return interpolatedBackgroundLevel(key, grid, p.x(), p.y());
  };
  const float inner = level(-1), outer = level(2);
  if (!(outer > inner)) return 0;
  const float half = 0.5f * (inner + outer);
  float lo = 0, hi = 1, at_lo = level(0), at_hi = level(1), f;
  if (at_lo >= half) {
    f = 0;
  } else if (at_hi < half) {
    f = 1;
  } else {
    for (int k = 0; k < 4; ++k) {
      const float mid = 0.5f * (lo + hi), at = level(mid);
      if (at >= half) {
        hi = mid, at_hi = at;
      } else {
        lo = mid, at_lo = at;
      }
    }
    f = lo + (half - at_lo) / (at_hi - at_lo) * (hi - lo);
  }
  return uint8_t(1 + std::lround(f * RefinementStatistics::kEdgeLevels));
}

// A camera's projection in floats, as the sampler's loops use it.
struct FloatProjection {
  explicit FloatProjection(const Camera& camera)
      : R(camera.rotation().cast<float>()),
        t(camera.translation().cast<float>()),
        fx(float(camera.intrinsics().fx)),
        fy(float(camera.intrinsics().fy)),
        cx(float(camera.intrinsics().cx)),
        cy(float(camera.intrinsics().cy)),
        skew(float(camera.intrinsics().skew)),
        distortion(camera.distortion()),
        distorted(!distortion.isZero()) {}
  Eigen::Vector3f toCamera(const Eigen::Vector3f& x) const { return R * x + t; }
  // A point in camera coordinates (in front of it) to its pixel position.
  Eigen::Vector2f pixel(const Eigen::Vector3f& c) const {
    float px = c.x() / c.z(), py = c.y() / c.z();
    if (distorted) distortion.apply(px, py, px, py);
    return Eigen::Vector2f(fx * px + skew * py + cx, fy * py + cy);
  }

  Eigen::Matrix3f R;
  Eigen::Vector3f t;
  float fx, fy, cx, cy, skew;
  const Distortion& distortion;
  bool distorted;
};

// Whether a camera keys the posed surface as the actor where the surface lies in its view: every
// fourth vertex's pixel keyed (about 500 pixels on the generic human, a few microseconds), at the
// projections its depth map made. Too few vertices in view to tell: it does.
template <typename Key>
bool seesTheSurface(const SamplerCamera& input, const Key& key, const DepthMap& depth) {
  const Eigen::Matrix2Xf& pixels = depth.vertexPixels();
  const float max_x = float(input.image.width) - 0.5f, max_y = float(input.image.height) - 0.5f;
  int in_view = 0, seen = 0;
  for (Eigen::Index v = 0; v < pixels.cols(); v += 4) {
    const float x = pixels(0, v), y = pixels(1, v);
    if (!(depth.vertexDepths()(v) > 0 && x >= -0.5f && y >= -0.5f && x < max_x && y < max_y))
      continue;
    ++in_view;
    seen += key.isForeground(input.image, int(x + 0.5f), int(y + 0.5f));
  }
  return in_view < RefinementSampler::kMinProbesInView ||
         float(seen) >= RefinementSampler::kMinSurfaceSeen * float(in_view);
}

// Marks the vertices that `camera` sees on its contour (RefineConfig::contour_cos,
// contour_probe_m): facing it at a grazing angle, not hidden in its depth map, and with the point
// a probe out along the normal falling where the posed mesh does not cover the map, so that
// nothing behind the vertex fills the camera's silhouette there. A few microseconds a camera: the
// map and the vertices' projections are the sampler's own.
void markContour(const Camera& camera, const DepthMap& depth, const RefineConfig& config,
                 const Eigen::Matrix3Xf& positions, const Eigen::Matrix3Xf& normals,
                 std::vector<uint8_t>& contour) {
  const FloatProjection projection(camera);
  const Eigen::Vector3f centre = camera.centre().cast<float>();
  const float max_cos = float(config.contour_cos), probe = float(config.contour_probe_m);
  const float tolerance = float(config.depth_tolerance_m);
  const Eigen::Matrix2Xf& pixels = depth.vertexPixels();
  const Eigen::VectorXf& depths = depth.vertexDepths();
  for (Eigen::Index v = 0; v < positions.cols(); ++v) {
    if (contour[v] || !(depths(v) > 0)) continue;
    const Eigen::Vector3f x = positions.col(v), nrm = normals.col(v), to_camera = centre - x;
    const float facing = nrm.dot(to_camera);
    if (!(facing > 0 && facing <= max_cos * to_camera.norm())) continue;
    if (!depth.visible(pixels(0, v), pixels(1, v), depths(v), tolerance)) continue;
    const Eigen::Vector3f c = projection.toCamera(x + probe * nrm);
    if (c.z() <= 0) continue;
    const Eigen::Vector2f p = projection.pixel(c);
    if (depth.depthAt(p.x(), p.y()) == DepthMap::kFar) contour[v] = 1;
  }
}

}  // namespace

Eigen::Vector3f windowDirection(const Eigen::Vector3f& normal) {
  const Eigen::Vector3f axis =
      std::abs(normal.z()) < 0.9f ? Eigen::Vector3f::UnitZ() : Eigen::Vector3f::UnitX();
  // The tangent nearest `axis`: the axis less its component along the normal.
  const Eigen::Vector3f t = axis - axis.dot(normal) * normal;
  const float length = t.norm();
  return length > 1e-6f ? Eigen::Vector3f(t / length) : Eigen::Vector3f::UnitX();
}

void RefinementSampler::sample(std::span<const SamplerCamera> cameras,
                               const Eigen::Matrix3Xf& positions, const Eigen::Matrix3Xf& normals,
                               const std::vector<Eigen::Vector3i>& triangles,
                               RefinementStatistics& out, std::span<const uint8_t> surface_levels) {
  const int n = static_cast<int>(positions.cols());
  // The surface the depth maps are made of: the posed mesh, or the posed mesh moved by the given
  // offsets.
  const bool refined = surface_levels.size() == size_t(n) && n > 0;
  if (refined) {
    applyOffsets(config_, surface_levels, positions, normals, surface_positions_);
    surface_m_.resize(size_t(n));  // for the window points, which lie off the vertices
    for (int v = 0; v < n; ++v) surface_m_[v] = float(config_.levelOffset(surface_levels[v]));
  }
  const Eigen::Matrix3Xf& surface = refined ? surface_positions_ : positions;
  const std::span<const float> surface_m =
      refined ? std::span<const float>(surface_m_) : std::span<const float>();
  const Eigen::Matrix3Xf* points = &positions;
  const Eigen::Matrix3Xf* point_normals = &normals;
  constexpr int kPoints = RefineConfig::kWindowPoints;  // the vertex, one side, the other
  if (config_.pointsPerVertex() == kPoints) {
    if (window_positions_.cols() != kPoints * n) {
      window_positions_.resize(3, kPoints * n);
      window_normals_.resize(3, kPoints * n);
    }
    const float w = float(config_.window_m);
    for (int v = 0; v < n; ++v) {
      const Eigen::Vector3f p = positions.col(v), nrm = normals.col(v);
      const Eigen::Vector3f along = w * windowDirection(nrm);
      window_positions_.col(v) = p;
      window_positions_.col(n + v) = p + along;
      window_positions_.col(2 * n + v) = p - along;
      for (int k = 0; k < kPoints; ++k) window_normals_.col(k * n + v) = nrm;
    }
    points = &window_positions_;
    point_normals = &window_normals_;
  }
  out.reset(int(points->cols()), config_.offset_count, config_.colour_bits);
  offsets_m_.resize(config_.offset_count);
  for (int i = 0; i < config_.offset_count; ++i) offsets_m_[i] = float(config_.offsetAt(i));
  if (depth_maps_.size() < cameras.size()) depth_maps_.resize(cameras.size());
  sees_nobody_.assign(cameras.size(), 0);
  for (size_t k = 0; k < cameras.size(); ++k) {
    const SamplerCamera& c = cameras[k];
    depth_maps_[k].render(*c.camera, surface, triangles, config_.depth_map_step);
    const auto sampleWith = [&](const auto& key) {
      if (!seesTheSurface(c, key, depth_maps_[k])) {
        sees_nobody_[k] = 1;
        return;
      }
      sampleCamera(c, key, depth_maps_[k], *points, *point_normals, surface_m, out);
      if (config_.marksContours())
        markContour(*c.camera, depth_maps_[k], config_, surface, normals, out.contour);
    };
    static const GreenScreenKeyer kDefaultKeyer;
    if (c.mask) {
      sampleWith(*c.mask);
    } else if (c.background) {
      sampleWith(*c.background);
    } else {
      sampleWith(c.green_screen ? *c.green_screen : kDefaultKeyer);
    }
  }
  out.dropOutside();
}

template <typename Key>
void RefinementSampler::sampleCamera(const SamplerCamera& input, const Key& key,
                                     const DepthMap& depth, const Eigen::Matrix3Xf& positions,
                                     const Eigen::Matrix3Xf& normals,
                                     std::span<const float> surface_m,
                                     RefinementStatistics& out) const {
  const ImageView& image = input.image;
  const FloatProjection projection(*input.camera);
  const Eigen::Vector3f centre = input.camera->centre().cast<float>();
  const float max_x = float(image.width) - 0.5f, max_y = float(image.height) - 0.5f;
  const int shift = 8 - config_.colour_bits;
  const float purity = float(config_.colour_purity);
  const int offsets = config_.offset_count;
  const float tolerance =
      float(surface_m.empty() ? config_.depth_tolerance_m : config_.refined_depth_tolerance_m);
  const float min_cos = float(config_.min_facing_cos);
  // Spill suppression: a green screen's only.
  const bool despill = config_.despill && std::is_same_v<Key, GreenScreenKeyer>;
  const int n = static_cast<int>(positions.cols());
  const int first_window = n / config_.pointsPerVertex();  // the points after the vertices
  const PixelGrid grid(image);
  for (int v = 0; v < n; ++v) {
    const Eigen::Vector3f x = positions.col(v), nrm = normals.col(v);
    // A line in the world is a line in camera coordinates: c(t) = c0 + t·d.
    const Eigen::Vector3f c0 = projection.toCamera(x), d = projection.R * nrm;
    const Eigen::Vector3f to_camera = centre - x;
    bool visible = nrm.dot(to_camera) > min_cos * to_camera.norm() && c0.z() > 0;
    if (visible) {
      // Tested where the depth map's surface crosses the normal.
      const Eigen::Vector3f c = surface_m.empty() ? c0 : c0 + surface_m[v % surface_m.size()] * d;
      const Eigen::Vector2f p = projection.pixel(c);
      visible = c.z() > 0 && depth.visible(p.x(), p.y(), c.z(), tolerance);
    }
    // A window point serves the colour term only: the cameras that do not see it say nothing
    // about it (a quarter less of a node's work, and leave-one-out as good).
    if (!visible && v >= first_window) continue;
    const size_t base = size_t(v) * offsets;
    // The previous sample's projection, while it was keyed as the actor: where the next is not,
    // this camera's silhouette edge lies between the two (a vertex's only: the window points serve
    // the colour term alone).
    bool previous_inside = false;
    Eigen::Vector2f previous = Eigen::Vector2f::Zero();
    // The offsets' projections lie on a smooth curve (the image of a line, bent a little by the
    // lens): a parabola through the projections of the range's ends and middle gives them within
    // a thousandth of a pixel on the reference rig (and through a strong lens: tested), saving
    // 1.5 of a node's 7.4 ms (refine_bench) against projecting each through the lens.
    const float t_lo = offsets_m_[0], t_hi = offsets_m_[offsets - 1];
    const float t_mid = 0.5f * (t_lo + t_hi), half = 0.5f * (t_hi - t_lo);
    // Both ends in front of the camera put the whole segment there.
    const Eigen::Vector3f c_lo = c0 + t_lo * d, c_hi = c0 + t_hi * d;
    const bool curve = offsets >= 3 && half > 0 && c_lo.z() > 0 && c_hi.z() > 0;
    Eigen::Vector2f p_mid = Eigen::Vector2f::Zero(), slope = p_mid, bend = p_mid;
    if (curve) {
      const Eigen::Vector2f p_lo = projection.pixel(c_lo), p_hi = projection.pixel(c_hi);
      p_mid = projection.pixel(c0 + t_mid * d);
      slope = (p_hi - p_lo) / (2 * half);
      bend = (p_hi + p_lo - 2 * p_mid) / (2 * half * half);
    }
    for (int i = 0; i < offsets; ++i) {
      float u, w;
      if (curve) {
        const float ti = offsets_m_[i] - t_mid;
        const Eigen::Vector2f p = p_mid + ti * (slope + ti * bend);
        u = p.x(), w = p.y();
      } else {
        const Eigen::Vector3f c = c0 + offsets_m_[i] * d;
        if (c.z() <= 0) {
          previous_inside = false;
          continue;
        }
        const Eigen::Vector2f p = projection.pixel(c);
        u = p.x(), w = p.y();
      }
      if (!(u >= -0.5f && w >= -0.5f && u < max_x && w < max_y)) {
        previous_inside = false;
        continue;
      }
      const int ix = static_cast<int>(u + 0.5f), iy = static_cast<int>(w + 0.5f);
      const size_t s = base + i;
      // Keyed between pixels: the key's background level interpolated at the projection, against
      // the key's bound at the nearest pixel. The nearest pixel's key (a Bayer cell's, on Bayer:
      // two pixels wide) carved the hull up to half a pixel (a pixel) inside the actor where a
      // pixel (cell) the actor covers in part fell to the screen: on Bayer sessions 28% of the
      // vertices ended more than 2 mm inside their best offset against 7% on RGB.
      const Neighbours around = grid.around(u, w);
      Rgb colours[4];
      grid.colours(around, colours);
      float levels[4];
      backgroundLevels(key, around, colours, levels);
      if (!key.isForegroundLevel(levelBetween(around, levels), ix, iy)) {
        ++out.outside[s];
        if (previous_inside && v < first_window) {
          uint8_t& edge = out.edges[s - 1];
          edge = RefinementStatistics::innerEdge(
              edge, locateEdge(key, grid, previous, Eigen::Vector2f(u, w)));
        }
        previous_inside = false;
        continue;
      }
      previous_inside = true;
      previous = Eigen::Vector2f(u, w);
      if (!visible) continue;
      uint32_t rgb[3];
      interpolatedColour(key, grid, around, colours, levels, ix, iy, shift, purity, rgb);
      if (despill) rgb[1] = std::min(rgb[1], std::max(rgb[0], rgb[2]));
      const uint32_t r = rgb[0], g = rgb[1], b = rgb[2];
      ++out.colour_count[s];
      out.sums[3 * s] = uint16_t(out.sums[3 * s] + r);
      out.sums[3 * s + 1] = uint16_t(out.sums[3 * s + 1] + g);
      out.sums[3 * s + 2] = uint16_t(out.sums[3 * s + 2] + b);
      out.squares[s] += r * r + g * g + b * b;
    }
  }
}

}  // namespace lumistage
