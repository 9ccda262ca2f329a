#pragma once

// A small scene whose truth is known exactly, for the refinement's tests: a textured ellipsoid
// filmed against a green screen by a ring of small cameras, and an icosphere inside it.

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <vector>

#include "core/body/skinned_mesh.h"
#include "core/capture/image.h"
#include "core/geometry/ring_rig.h"
#include "core/refine/refine_config.h"
#include "core/refine/refinement_statistics.h"

namespace lumistage::testing {

struct Ellipsoid {
  Eigen::Vector3d centre{0, 0, 1.0};
  Eigen::Vector3d radii{0.32, 0.30, 0.28};

  // Distance along the ray to the first hit, or < 0.
  double hit(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
    const Eigen::Vector3d o = (origin - centre).cwiseQuotient(radii);
    const Eigen::Vector3d d = direction.cwiseQuotient(radii);
    const double a = d.dot(d), b = 2 * o.dot(d), c = o.dot(o) - 1;
    const double disc = b * b - 4 * a * c;
    if (disc < 0) return -1;
    return (-b - std::sqrt(disc)) / (2 * a);
  }
  // Radius of the surface in a direction from the centre.
  double radiusAlong(const Eigen::Vector3d& unit) const {
    return 1.0 / unit.cwiseQuotient(radii).norm();
  }
};

// A colourful texture anchored on the surface, patches a few centimetres across (like printed
// cloth).
inline void textureAt(const Eigen::Vector3d& p, uint8_t rgb[3]) {
  const double s = std::sin(p.x() * 25) * std::sin(p.y() * 23) * std::sin(p.z() * 27);
  const double u = std::sin(p.x() * 9 + p.z() * 11);
  rgb[0] = uint8_t(128 + 110 * s);
  rgb[1] = uint8_t(60 + 40 * u);
  rgb[2] = uint8_t(128 - 100 * s * u);
}

inline Rig smallRing(int width = 320, int height = 240) {
  RingRigSpec spec;
  spec.width = width;
  spec.height = height;
  spec.radius_m = 2.0;
  spec.target_m = {0, 0, 1.0};
  spec.vertical_fov_deg = 40;
  return makeRingRig(spec);
}

// Every camera's RGB image of the ellipsoid over a green screen: one ray a pixel, or the mean of
// samples x samples rays spread over it (a sensor's pixel, whose edges mix the two colours).
inline std::vector<Image> renderEllipsoid(const Rig& rig, const Ellipsoid& shape, int samples = 1) {
  std::vector<Image> images(rig.cameraCount());
  for (int c = 0; c < rig.cameraCount(); ++c) {
    const Camera& cam = rig.camera(c);
    images[c].resize(PixelFormat::kRgb8, cam.width(), cam.height());
    for (int y = 0; y < cam.height(); ++y) {
      for (int x = 0; x < cam.width(); ++x) {
        int sum[3] = {0, 0, 0};
        for (int k = 0; k < samples * samples; ++k) {
          uint8_t rgb[3] = {40, 150, 60};
          const Eigen::Vector2d at = samples == 1
                                         ? Eigen::Vector2d(x, y)
                                         : Eigen::Vector2d(x - 0.5 + (k % samples + 0.5) / samples,
                                                           y - 0.5 + (k / samples + 0.5) / samples);
          const std::optional<Ray> ray = cam.unproject(at);
          const double t = ray ? shape.hit(ray->origin, ray->direction) : -1;
          if (t > 0) textureAt(ray->origin + t * ray->direction, rgb);
          for (int ch = 0; ch < 3; ++ch) sum[ch] += rgb[ch];
        }
        uint8_t* out = &images[c].pixels[3 * (size_t(y) * cam.width() + x)];
        for (int ch = 0; ch < 3; ++ch)
          out[ch] = uint8_t((sum[ch] + samples * samples / 2) / (samples * samples));
      }
    }
  }
  return images;
}

// An icosphere: a subdivided icosahedron, outward normals.
inline TriangleMesh icosphere(const Eigen::Vector3d& centre, double radius, int subdivisions) {
  const double g = (1 + std::sqrt(5.0)) / 2;
  std::vector<Eigen::Vector3d> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                                    {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                                    {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  for (auto& p : v) p.normalize();
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> mid;
    auto middle = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> next;
    for (const Eigen::Vector3i& t : f) {
      const int a = middle(t[0], t[1]), b = middle(t[1], t[2]), c = middle(t[2], t[0]);
      next.push_back({t[0], a, c});
      next.push_back({t[1], b, a});
      next.push_back({t[2], c, b});
      next.push_back({a, b, c});
    }
    f = next;
  }
  TriangleMesh mesh;
  mesh.positions.resize(3, v.size());
  for (size_t i = 0; i < v.size(); ++i)
    mesh.positions.col(i) = (centre + radius * v[i]).cast<float>();
  mesh.triangles = f;
  mesh.normals.resize(3, v.size());
  for (size_t i = 0; i < v.size(); ++i) mesh.normals.col(i) = v[i].cast<float>();
  return mesh;
}

// Where the sampler located the hull's edge against where the true hull of `shape` leaves each
// vertex's normal: over the samples where the hull leaves (`leaving`) and those of them that hold a
// located edge (`edges`), the mean distance of the located edge (`located`) and of the point
// halfway between the two samples (`halfway`) from the true crossing, metres.
struct EdgeDistances {
  double located = 0, halfway = 0;
  int edges = 0, leaving = 0;
};
inline EdgeDistances hullEdgeDistances(const Rig& rig, const Ellipsoid& shape,
                                       const TriangleMesh& sphere, const RefineConfig& config,
                                       const RefinementStatistics& stats) {
  // The true hull: inside while every camera's ray through the point meets the ellipsoid.
  const auto inside = [&](const Eigen::Vector3d& p) {
    for (int c = 0; c < rig.cameraCount(); ++c) {
      const Eigen::Vector3d o = rig.camera(c).centre();
      if (shape.hit(o, (p - o).normalized()) <= 0) return false;
    }
    return true;
  };
  const double step = config.offsetAt(1) - config.offsetAt(0);
  EdgeDistances out;
  for (int v = 0; v < sphere.vertexCount(); ++v) {
    const Eigen::Vector3d p = sphere.positions.col(v).cast<double>(),
                          n = sphere.normals.col(v).cast<double>();
    for (int i = 0; i + 1 < config.offset_count; ++i) {
      const size_t s = size_t(v) * config.offset_count + i;
      if (!stats.leavesHull(s)) continue;
      ++out.leaving;
      double lo = config.offsetAt(i) - step, hi = config.offsetAt(i + 1) + step;
      if (!inside(p + lo * n) || inside(p + hi * n)) continue;
      for (int k = 0; k < 40; ++k) (inside(p + 0.5 * (lo + hi) * n) ? lo : hi) = 0.5 * (lo + hi);
      if (stats.edges[s] == 0) continue;
      ++out.edges;
      const double at =
          config.offsetAt(i) + step * (stats.edges[s] - 1) / RefinementStatistics::kEdgeLevels;
      out.located += std::abs(at - lo);
      out.halfway += std::abs(config.offsetAt(i) + step / 2 - lo);
    }
  }
  if (out.edges > 0) out.located /= out.edges, out.halfway /= out.edges;
  return out;
}

}  // namespace lumistage::testing
