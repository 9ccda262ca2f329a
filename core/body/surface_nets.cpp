#include "core/body/surface_nets.h"

#include <cmath>
#include <stdexcept>
#include <vector>

namespace lumistage {

TriangleMesh extractSurface(const std::function<float(const Eigen::Vector3f&)>& sdf,
                            const Eigen::AlignedBox3f& bounds, float cell_m) {
  if (!(cell_m > 0) || bounds.isEmpty()) throw std::invalid_argument("extractSurface: empty grid");
  const Eigen::Vector3f origin = bounds.min();
  const Eigen::Vector3i n =
      ((bounds.max() - origin) / cell_m).array().ceil().cast<int>() + 1;  // samples
  auto index = [&](int i, int j, int k) { return (size_t(k) * n.y() + j) * n.x() + i; };
  auto point = [&](int i, int j, int k) {
    return Eigen::Vector3f(origin + cell_m * Eigen::Vector3f(i, j, k));
  };

  std::vector<float> value(size_t(n.x()) * n.y() * n.z());
  for (int k = 0; k < n.z(); ++k) {
    for (int j = 0; j < n.y(); ++j) {
      for (int i = 0; i < n.x(); ++i) value[index(i, j, k)] = sdf(point(i, j, k));
    }
  }

  // One vertex per cell with a sign change; cells indexed by their lowest corner.
  std::vector<int> cell_vertex(value.size(), -1);
  std::vector<Eigen::Vector3f> vertices;
  static const int kCorner[8][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0},
                                    {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
  static const int kEdge[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                   {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  for (int k = 0; k + 1 < n.z(); ++k) {
    for (int j = 0; j + 1 < n.y(); ++j) {
      for (int i = 0; i + 1 < n.x(); ++i) {
        float v[8];
        int inside = 0;
        for (int c = 0; c < 8; ++c) {
          v[c] = value[index(i + kCorner[c][0], j + kCorner[c][1], k + kCorner[c][2])];
          inside += v[c] < 0;
        }
        if (inside == 0 || inside == 8) continue;
        Eigen::Vector3f sum = Eigen::Vector3f::Zero();
        int crossings = 0;
        for (const auto& e : kEdge) {
          const float a = v[e[0]], b = v[e[1]];
          if ((a < 0) == (b < 0)) continue;
          const float t = a / (a - b);
          const Eigen::Vector3f pa(kCorner[e[0]][0], kCorner[e[0]][1], kCorner[e[0]][2]);
          const Eigen::Vector3f pb(kCorner[e[1]][0], kCorner[e[1]][1], kCorner[e[1]][2]);
          sum += pa + t * (pb - pa);
          ++crossings;
        }
        Eigen::Vector3f p = point(i, j, k) + cell_m * sum / float(crossings);
        // Pull onto the surface along the gradient (a few Newton steps), staying in the cell.
        const float h = 0.05f * cell_m;
        for (int step = 0; step < 3; ++step) {
          const float f = sdf(p);
          const Eigen::Vector3f g(
              (sdf(p + Eigen::Vector3f(h, 0, 0)) - sdf(p - Eigen::Vector3f(h, 0, 0))) / (2 * h),
              (sdf(p + Eigen::Vector3f(0, h, 0)) - sdf(p - Eigen::Vector3f(0, h, 0))) / (2 * h),
              (sdf(p + Eigen::Vector3f(0, 0, h)) - sdf(p - Eigen::Vector3f(0, 0, h))) / (2 * h));
          const float g2 = g.squaredNorm();
          if (g2 < 1e-12f) break;
          p -= f * g / g2;
        }
        const Eigen::Vector3f lo = point(i, j, k), hi = point(i + 1, j + 1, k + 1);
        p = p.cwiseMax(lo).cwiseMin(hi);
        cell_vertex[index(i, j, k)] = static_cast<int>(vertices.size());
        vertices.push_back(p);
      }
    }
  }

  // One quad per grid edge with a sign change, joining the four cells around it, counter-
  // clockwise seen from outside (from the positive side).
  TriangleMesh mesh;
  auto addQuad = [&](int a, int b, int c, int d, bool flip) {
    if (flip) std::swap(b, d);
    // Split along the shorter diagonal: better triangles.
    if ((vertices[a] - vertices[c]).squaredNorm() <= (vertices[b] - vertices[d]).squaredNorm()) {
      mesh.triangles.emplace_back(a, b, c);
      mesh.triangles.emplace_back(a, c, d);
    } else {
      mesh.triangles.emplace_back(a, b, d);
      mesh.triangles.emplace_back(b, c, d);
    }
  };
  for (int k = 1; k + 1 < n.z(); ++k) {
    for (int j = 1; j + 1 < n.y(); ++j) {
      for (int i = 1; i + 1 < n.x(); ++i) {
        const bool here = value[index(i, j, k)] < 0;
        if (here != (value[index(i + 1, j, k)] < 0)) {  // edge along x
          addQuad(cell_vertex[index(i, j - 1, k - 1)], cell_vertex[index(i, j, k - 1)],
                  cell_vertex[index(i, j, k)], cell_vertex[index(i, j - 1, k)], !here);
        }
        if (here != (value[index(i, j + 1, k)] < 0)) {  // edge along y: plane (z, x)
          addQuad(cell_vertex[index(i - 1, j, k - 1)], cell_vertex[index(i - 1, j, k)],
                  cell_vertex[index(i, j, k)], cell_vertex[index(i, j, k - 1)], !here);
        }
        if (here != (value[index(i, j, k + 1)] < 0)) {  // edge along z: plane (x, y)
          addQuad(cell_vertex[index(i - 1, j - 1, k)], cell_vertex[index(i, j - 1, k)],
                  cell_vertex[index(i, j, k)], cell_vertex[index(i - 1, j, k)], !here);
        }
      }
    }
  }
  mesh.positions.resize(3, vertices.size());
  for (size_t v = 0; v < vertices.size(); ++v) mesh.positions.col(v) = vertices[v];
  mesh.computeNormals();
  return mesh;
}

}  // namespace lumistage
