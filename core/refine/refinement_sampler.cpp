#include "core/refine/refinement_sampler.h"

#include <algorithm>
#include <cmath>

namespace lumistage {

namespace {

// The key's background level (GreenScreenKeyer::backgroundLevel) at pixel position (u, w), pixel
// centres at integers: bilinear between pixels, or between the 2x2 cells of a Bayer image (the key
// reads a cell's colour), clamped to the image.
template <typename Key>
float interpolatedBackgroundLevel(const Key& key, const ImageView& image, float u, float w) {
  const int step = isBayer(image.format) ? 2 : 1;
  const int columns = image.width / step, rows = image.height / step;
  // A Bayer cell k holds pixels 2k and 2k + 1: its centre is at 2k + 0.5.
  const float x = std::clamp(step == 2 ? (u - 0.5f) * 0.5f : u, 0.0f, float(columns - 1));
  const float y = std::clamp(step == 2 ? (w - 0.5f) * 0.5f : w, 0.0f, float(rows - 1));
  const int x0 = std::max(0, std::min(int(x), columns - 2)),
            y0 = std::max(0, std::min(int(y), rows - 2));
  const int x1 = std::min(x0 + 1, columns - 1), y1 = std::min(y0 + 1, rows - 1);
  const float fx = x - float(x0), fy = y - float(y0);
  const auto at = [&](int cx, int cy) {
    return float(key.backgroundLevel(image, cx * step, cy * step));
  };
  return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x1, y0)) +
         fy * ((1 - fx) * at(x0, y1) + fx * at(x1, y1));
}

// Where a camera's silhouette edge lies between the projections `a` (keyed actor) and `b` (keyed
// background) of two consecutive samples, below a pixel: the fraction of the way from a to b where
// the interpolated background level is halfway between the actor's and the background's (read a
// step further in and out: the pixels at a and b may be mixed), i.e. where the actor covers half a
// pixel. As an edge byte (RefinementStatistics::edges), 0 when the two sides do not differ.
template <typename Key>
uint8_t locateEdge(const Key& key, const ImageView& image, const Eigen::Vector2f& a,
                   const Eigen::Vector2f& b) {
  const Eigen::Vector2f d = b - a;
  const auto level = [&](float f) {
    const Eigen::Vector2f p = a + f * d;
    return interpolatedBackgroundLevel(key, image, p.x(), p.y());
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
                               RefinementStatistics& out) {
  const int n = static_cast<int>(positions.cols());
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
  for (size_t k = 0; k < cameras.size(); ++k) {
    const SamplerCamera& c = cameras[k];
    depth_maps_[k].render(*c.camera, positions, triangles, config_.depth_map_step);
    if (c.background) {
      sampleCamera(c, *c.background, depth_maps_[k], *points, *point_normals, out);
    } else {
      static const GreenScreenKeyer kDefaultKeyer;
      sampleCamera(c, c.green_screen ? *c.green_screen : kDefaultKeyer, depth_maps_[k], *points,
                   *point_normals, out);
    }
  }
  out.dropOutside();
}

template <typename Key>
void RefinementSampler::sampleCamera(const SamplerCamera& input, const Key& key,
                                     const DepthMap& depth, const Eigen::Matrix3Xf& positions,
                                     const Eigen::Matrix3Xf& normals,
                                     RefinementStatistics& out) const {
  const Camera& camera = *input.camera;
  const ImageView& image = input.image;
  const Eigen::Matrix3f R = camera.rotation().cast<float>();
  const Eigen::Vector3f t = camera.translation().cast<float>();
  const Eigen::Vector3f centre = camera.centre().cast<float>();
  const Intrinsics& K = camera.intrinsics();
  const float fx = float(K.fx), fy = float(K.fy), cx = float(K.cx), cy = float(K.cy),
              skew = float(K.skew);
  const Distortion& dist = camera.distortion();
  const bool distorted = !dist.isZero();
  const float max_x = float(image.width) - 0.5f, max_y = float(image.height) - 0.5f;
  const int shift = 8 - config_.colour_bits;
  const int offsets = config_.offset_count;
  const float tolerance = float(config_.depth_tolerance_m);
  const float min_cos = float(config_.min_facing_cos);
  const int n = static_cast<int>(positions.cols());
  const int first_window = n / config_.pointsPerVertex();  // the points after the vertices
  for (int v = 0; v < n; ++v) {
    const Eigen::Vector3f x = positions.col(v), nrm = normals.col(v);
    // A line in the world is a line in camera coordinates: c(t) = c0 + t·d.
    const Eigen::Vector3f c0 = R * x + t, d = R * nrm;
    const Eigen::Vector3f to_camera = centre - x;
    bool visible = nrm.dot(to_camera) > min_cos * to_camera.norm() && c0.z() > 0;
    if (visible) {
      float px = c0.x() / c0.z(), py = c0.y() / c0.z();
      if (distorted) dist.apply(px, py, px, py);
      visible = depth.visible(fx * px + skew * py + cx, fy * py + cy, c0.z(), tolerance);
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
    for (int i = 0; i < offsets; ++i) {
      const Eigen::Vector3f c = c0 + offsets_m_[i] * d;
      if (c.z() <= 0) {
        previous_inside = false;
        continue;
      }
      float px = c.x() / c.z(), py = c.y() / c.z();
      if (distorted) dist.apply(px, py, px, py);
      const float u = fx * px + skew * py + cx, w = fy * py + cy;
      if (!(u >= -0.5f && w >= -0.5f && u < max_x && w < max_y)) {
        previous_inside = false;
        continue;
      }
      const int ix = static_cast<int>(u + 0.5f), iy = static_cast<int>(w + 0.5f);
      const size_t s = base + i;
      if (!key.isForeground(image, ix, iy)) {
        ++out.outside[s];
        if (previous_inside && v < first_window) {
          uint8_t& edge = out.edges[s - 1];
          edge = RefinementStatistics::innerEdge(
              edge, locateEdge(key, image, previous, Eigen::Vector2f(u, w)));
        }
        previous_inside = false;
        continue;
      }
      previous_inside = true;
      previous = Eigen::Vector2f(u, w);
      if (!visible) continue;
      const Rgb rgb = colourAt(image, ix, iy);
      const uint32_t r = uint32_t(rgb.r) >> shift, g = uint32_t(rgb.g) >> shift,
                     b = uint32_t(rgb.b) >> shift;
      ++out.colour_count[s];
      out.sums[3 * s] = uint16_t(out.sums[3 * s] + r);
      out.sums[3 * s + 1] = uint16_t(out.sums[3 * s + 1] + g);
      out.sums[3 * s + 2] = uint16_t(out.sums[3 * s + 2] + b);
      out.squares[s] += r * r + g * g + b * b;
    }
  }
}

}  // namespace lumistage
