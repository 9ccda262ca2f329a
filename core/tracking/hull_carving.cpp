// The tracker's visual hull (PoseTracker::Impl, pose_tracker_impl.h): every camera's silhouette
// made a distance transform, and the hull carved from them on the stage's voxel grid through the
// lookup tables the constructor builds, a block of voxels at a time where a camera sees it empty,
// its surface sampled.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/tracking/pose_tracker_impl.h"

namespace lumistage {

namespace {

// Squared Euclidean distance transform in 1D (Felzenszwalb & Huttenlocher).
void edt1d(const float* f, int n, float* d, int* v, float* z) {
  int k = 0;
  v[0] = 0;
  z[0] = -std::numeric_limits<float>::infinity();
  z[1] = std::numeric_limits<float>::infinity();
  for (int q = 1; q < n; ++q) {
    float s;
    while (true) {
      s = ((f[q] + float(q) * q) - (f[v[k]] + float(v[k]) * v[k])) / (2.0f * (q - v[k]));
      if (s <= z[k] && k > 0) {
        --k;
      } else {
        break;
      }
    }
    if (s <= z[k]) {  // k == 0
      v[0] = q;
      z[0] = -std::numeric_limits<float>::infinity();
      z[1] = std::numeric_limits<float>::infinity();
      continue;
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = std::numeric_limits<float>::infinity();
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < q) ++k;
    d[q] = float(q - v[k]) * float(q - v[k]) + f[v[k]];
  }
}

}  // namespace

using namespace tracker_detail;

void PoseTracker::Impl::prepareSilhouettes(
    const std::vector<const LowResSilhouette*>& silhouettes) {
  std::fill(present.begin(), present.end(), 0);
  frame_silhouettes.assign(size_t(cameras), nullptr);
  rim.clear();
  candidates_valid = false;  // the rim's candidates with it
  int given_count = 0;
  for (const LowResSilhouette* s : silhouettes) given_count += s != nullptr;
  const int rim_per_camera =
      given_count > 0 ? std::max(opt.min_rim_rays_per_camera, opt.rim_rays / given_count) : 0;
  const float inf = 1e10f;
  for (const LowResSilhouette* s : silhouettes) {
    if (!s || s->camera < 0 || s->camera >= cameras || s->step != opt.silhouette_step ||
        s->width != cell_w[s->camera] || s->height != cell_h[s->camera] ||
        s->bits.size() * 8 < size_t(s->width) * s->height) {
      continue;
    }
    const int c = s->camera, w = s->width, h = s->height;
    present[c] = 1;
    frame_silhouettes[size_t(c)] = s;
    std::vector<float>& d = dt[c];
    Eigen::Array4i& box = dt_box[c];
    for (int y = box[1]; y <= box[3]; ++y)
      std::fill_n(&d[size_t(y) * w + box[0]], box[2] - box[0] + 1, kFarCells);
    // The silhouette's bounding box, a byte of cells at a time.
    box = Eigen::Array4i(w, h, -1, -1);
    const size_t cells = size_t(w) * h;
    for (size_t b = 0; b * 8 < cells; ++b) {
      if (!s->bits[b]) continue;
      for (int k = 0; k < 8; ++k) {
        const size_t i = b * 8 + k;
        if (i >= cells || !((s->bits[b] >> k) & 1)) continue;
        const int x = int(i % w), y = int(i / w);
        box = box.min(Eigen::Array4i(x, y, w, h)).max(Eigen::Array4i(-1, -1, x, y));
      }
    }
    if (box[2] < box[0]) continue;  // nobody in view: every cell is far outside
    if (opt.rim_weight > 0) sampleRim(*s, rim_per_camera);
    box = (box + Eigen::Array4i(-kDtMargin, -kDtMargin, kDtMargin, kDtMargin))
              .max(Eigen::Array4i::Zero())
              .min(Eigen::Array4i(w - 1, h - 1, w - 1, h - 1));
    const int bw = box[2] - box[0] + 1, bh = box[3] - box[1] + 1;
    // Columns, then rows: squared distance to the nearest cell inside the silhouette.
    for (int x = box[0]; x <= box[2]; ++x) {
      for (int y = 0; y < bh; ++y) dt_f[y] = s->at(x, box[1] + y) ? 0.0f : inf;
      edt1d(dt_f.data(), bh, dt_d.data(), dt_v.data(), dt_z.data());
      for (int y = 0; y < bh; ++y) d[size_t(box[1] + y) * w + x] = dt_d[y];
    }
    for (int y = box[1]; y <= box[3]; ++y) {
      float* r = &d[size_t(y) * w + box[0]];
      std::copy(r, r + bw, dt_f.begin());
      edt1d(dt_f.data(), bw, dt_d.data(), dt_v.data(), dt_z.data());
      for (int x = 0; x < bw; ++x) r[x] = std::sqrt(std::min(dt_d[x], kFarCells * kFarCells));
    }
  }
  // A camera that sees nobody while most see someone (covered by the screen's colour, bumped to
  // the wall, its key broken) would carve away every voxel it sees, the actor's too, and the
  // tracker would see nobody: it is left out of this frame's hull, and said once. (An actor
  // outside a camera's view needs no such camera: voxels it cannot see get no vote from it.)
  const auto seesSomeone = [&](int c) { return dt_box[c][2] >= dt_box[c][0]; };
  int given = 0, with_someone = 0;
  for (int c = 0; c < cameras; ++c) {
    given += present[c];
    with_someone += present[c] && seesSomeone(c);
  }
  for (int c = 0; c < cameras; ++c) {
    if (!present[c]) continue;
    if (seesSomeone(c)) {
      told_empty[c] = 0;
    } else if (with_someone >= 3 && 2 * with_someone > given) {
      present[c] = 0;
      if (!told_empty[c]) {
        told_empty[c] = 1;
        spdlog::warn(
            "tracker: camera {} sees nobody while {} of {} cameras see the actor: left out of the "
            "hull until it sees someone again (covered, moved, or its key broken?)",
            rig.camera(c).name(), with_someone, given);
      }
    }
  }
}

template <typename T>
int PoseTracker::Impl::blockReach2(const std::vector<T>& table, const Eigen::Vector3i& first,
                                   const Eigen::Vector3i& last, int c) const {
  const size_t sy = size_t(dims.x()), sz = size_t(dims.x()) * dims.y();
  const T ref = table[(first.z() * sz + first.y() * sy + first.x()) * cameras + c];
  const int w = cell_w[c], rx = int(ref % w), ry = int(ref / w);
  int reach2 = 0;
  for (int z = first.z(); z <= last.z(); ++z) {
    for (int y = first.y(); y <= last.y(); ++y) {
      for (int x = first.x(); x <= last.x(); ++x) {
        const T at = table[(z * sz + y * sy + x) * cameras + c];
        if (at == kUnseen<T>) return -1;
        const int dx = int(at % w) - rx, dy = int(at / w) - ry;
        reach2 = std::max(reach2, dx * dx + dy * dy);
      }
    }
  }
  return reach2;
}

template <typename T>
void PoseTracker::Impl::makeBlocks(const std::vector<T>& table) {
  block_dims = blocksOf(dims);
  const size_t blocks = size_t(block_dims.x()) * block_dims.y() * block_dims.z();
  block_cell.assign(blocks * cameras, kUnseen<uint32_t>);
  block_reach.assign(blocks * cameras, 0);
  const size_t sy = size_t(dims.x()), sz = size_t(dims.x()) * dims.y();
  size_t b = 0;
  for (int bz = 0; bz < block_dims.z(); ++bz) {
    for (int by = 0; by < block_dims.y(); ++by) {
      for (int bx = 0; bx < block_dims.x(); ++bx, ++b) {
        const Eigen::Vector3i first(bx * kBlock, by * kBlock, bz * kBlock);
        const Eigen::Vector3i last = (first.array() + kBlock - 1).min(dims.array() - 1);
        const size_t v = first.z() * sz + first.y() * sy + first.x();
        for (int c = 0; c < cameras; ++c) {
          const int reach2 = blockReach2(table, first, last, c);
          const int reach = reach2 < 0 ? 256 : int(std::ceil(std::sqrt(double(reach2))));
          if (reach > 255) continue;  // not seen whole, or too wide to carve at once
          block_cell[b * cameras + c] = uint32_t(table[v * cameras + c]);
          block_reach[b * cameras + c] = uint8_t(reach);
        }
      }
    }
  }
}

double PoseTracker::Impl::carve(Eigen::Vector3i lo, Eigen::Vector3i hi, Eigen::Vector3d* centroid,
                                double* top_z, double* bottom_z) {
  lo = lo.cwiseMax(Eigen::Vector3i::Zero());
  hi = hi.cwiseMin(dims - Eigen::Vector3i::Ones());
  clearOccupied();
  surface_all.clear();
  hull.clear();
  candidates_valid = false;
  if ((hi.array() < lo.array()).any()) return 0;
  const size_t sx = 1, sy = size_t(dims.x()), sz = size_t(dims.x()) * dims.y();
  int count = 0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double top = 0, bottom = dims.z();
  // The kept voxels' box: only it is scanned for the surface and cleared after (the region around
  // a body is ten times its box, the stage's a hundred).
  Eigen::Vector3i kept_lo = hi, kept_hi = lo;
  // The camera that carved the last voxel away is asked first: neighbouring voxels mostly fall
  // outside the same silhouette.
  int first = 0;
  // Whether camera c carves all of block b away: its distance transform at the block's cell
  // beyond the block's reach (outside the transform's box, the silhouette is more than kDtMargin
  // cells away).
  const auto carvesBlock = [&](size_t b, int c) {
    const uint32_t at = block_cell[b * cameras + c];
    if (!present[c] || at == kUnseen<uint32_t>) return false;
    const float d = dt[c][at];
    return (d >= kFarCells ? float(kDtMargin) : d) > float(block_reach[b * cameras + c]);
  };
  const auto carveWith = [&]<typename T>(const std::vector<T>& table, const Eigen::Vector3i& from,
                                         const Eigen::Vector3i& to) {
    for (int z = from.z(); z <= to.z(); ++z) {
      for (int y = from.y(); y <= to.y(); ++y) {
        size_t v = z * sz + y * sy + from.x() * sx;
        for (int x = from.x(); x <= to.x(); ++x, ++v) {
          const T* cells = &table[v * cameras];
          int seen = 0;
          bool inside = true;
          for (int k = 0; k < cameras; ++k) {
            const int c = k == 0 ? first : (k <= first ? k - 1 : k);
            if (!present[c] || cells[c] == kUnseen<T>) continue;
            ++seen;
            const float d = dt[c][cells[c]];
            if (d > 0) {
              inside = false;
              first = c;
              break;
            }
          }
          const bool keep = inside && seen >= 2;
          occupied[v] = keep;
          if (keep) {
            ++count;
            sum += Eigen::Vector3d(x, y, z);
            top = std::max(top, double(z));
            bottom = std::min(bottom, double(z));
            kept_lo = kept_lo.cwiseMin(Eigen::Vector3i(x, y, z));
            kept_hi = kept_hi.cwiseMax(Eigen::Vector3i(x, y, z));
          }
        }
      }
    }
  };
  const Eigen::Vector3i block_lo = lo / kBlock, block_hi = hi / kBlock;
  for (int bz = block_lo.z(); bz <= block_hi.z(); ++bz) {
    for (int by = block_lo.y(); by <= block_hi.y(); ++by) {
      for (int bx = block_lo.x(); bx <= block_hi.x(); ++bx) {
        const size_t b = (size_t(bz) * block_dims.y() + by) * block_dims.x() + bx;
        bool carved = carvesBlock(b, first);
        for (int c = 0; c < cameras && !carved; ++c) {
          if (c != first && carvesBlock(b, c)) carved = true, first = c;
        }
        if (carved) continue;  // its voxels stay unoccupied
        const Eigen::Vector3i from = (Eigen::Vector3i(bx, by, bz) * kBlock).cwiseMax(lo);
        const Eigen::Vector3i to =
            (Eigen::Vector3i(bx, by, bz) * kBlock + Eigen::Vector3i::Constant(kBlock - 1))
                .cwiseMin(hi);
        if (cell_wide.empty()) {
          carveWith(cell, from, to);
        } else {
          carveWith(cell_wide, from, to);
        }
      }
    }
  }
  if (count == 0) kept_lo = hi + Eigen::Vector3i::Ones(), kept_hi = hi;  // nothing to scan
  occupied_lo = kept_lo, occupied_hi = kept_hi;  // cleared by the next carve
  sampleSurface(lo, hi);
  if (centroid && count > 0)
    *centroid = lower + opt.voxel_m * (sum / count + Eigen::Vector3d::Constant(0.5));
  if (top_z) *top_z = lower.z() + opt.voxel_m * (top + 1.0);
  if (bottom_z) *bottom_z = lower.z() + opt.voxel_m * (count > 0 ? bottom : 0.0);
  return count * std::pow(opt.voxel_m, 3);
}

void PoseTracker::Impl::sampleSurface(const Eigen::Vector3i& lo, const Eigen::Vector3i& hi) {
  surface_all.clear();
  hull.clear();
  candidates_valid = false;
  const size_t sy = size_t(dims.x()), sz = size_t(dims.x()) * dims.y();
  // Surface voxels: kept, with a 6-neighbour that is not (the region's border and the floor
  // count as empty). The sample moves half a voxel toward its empty neighbours: onto the hull's
  // boundary, on average, rather than inside it.
  for (int z = occupied_lo.z(); z <= occupied_hi.z(); ++z) {
    for (int y = occupied_lo.y(); y <= occupied_hi.y(); ++y) {
      for (int x = occupied_lo.x(); x <= occupied_hi.x(); ++x) {
        const size_t v = z * sz + y * sy + x;
        if (!occupied[v]) continue;
        Eigen::Vector3d n = Eigen::Vector3d::Zero();
        if (x == lo.x() || !occupied[v - 1]) n.x() -= 1;
        if (x == hi.x() || !occupied[v + 1]) n.x() += 1;
        if (y == lo.y() || !occupied[v - sy]) n.y() -= 1;
        if (y == hi.y() || !occupied[v + sy]) n.y() += 1;
        if (z == lo.z() || !occupied[v - sz]) n.z() -= 1;
        if (z == hi.z() || !occupied[v + sz]) n.z() += 1;
        const double len = n.norm();
        if (len == 0) continue;
        surface_all.push_back(
            lower + opt.voxel_m * (Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5) + 0.5 * n / len));
      }
    }
  }
  const size_t n = surface_all.size(), m = size_t(opt.max_hull_points);
  if (n <= m) {
    hull = surface_all;
  } else {
    for (size_t i = 0; i < m; ++i) hull.push_back(surface_all[i * n / m]);
  }
}

void PoseTracker::Impl::clearOccupied() {
  const size_t sy = size_t(dims.x()), sz = size_t(dims.x()) * dims.y();
  for (int z = occupied_lo.z(); z <= occupied_hi.z(); ++z) {
    for (int y = occupied_lo.y(); y <= occupied_hi.y(); ++y)
      std::fill_n(&occupied[z * sz + y * sy + occupied_lo.x()],
                  occupied_hi.x() - occupied_lo.x() + 1, 0);
  }
  occupied_lo = Eigen::Vector3i::Zero(), occupied_hi = -Eigen::Vector3i::Ones();
}

template void PoseTracker::Impl::makeBlocks<uint16_t>(const std::vector<uint16_t>& table);
template void PoseTracker::Impl::makeBlocks<uint32_t>(const std::vector<uint32_t>& table);

}  // namespace lumistage
