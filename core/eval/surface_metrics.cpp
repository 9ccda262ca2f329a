#include "core/eval/surface_metrics.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/body/joint_pose_fit.h"
#include "core/body/ply_mesh.h"
#include "core/capture/session_reader.h"
#include "core/eval/percentile.h"
#include "core/imaging/clean_plate.h"
#include "core/refine/frame_refiner.h"

namespace lumistage {

namespace {

// Ericson, Real-Time Collision Detection, 5.1.5: the closest point of triangle abc to p.
Eigen::Vector3d closestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                  const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

}  // namespace

SurfaceDistance::SurfaceDistance(const TriangleMesh& mesh, double cell_m) : cell_(cell_m) {
  vertices_.resize(mesh.vertexCount());
  for (int v = 0; v < mesh.vertexCount(); ++v) vertices_[v] = mesh.positions.col(v).cast<double>();
  triangles_ = mesh.triangles;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e30), hi = Eigen::Vector3d::Constant(-1e30);
  for (const Eigen::Vector3d& v : vertices_) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  if (vertices_.empty()) lo = hi = Eigen::Vector3d::Zero();
  const double margin = 0.25;  // queries come from near the surface
  origin_ = lo - Eigen::Vector3d::Constant(margin);
  for (int k = 0; k < 3; ++k)
    size_[k] = std::max(1, static_cast<int>(std::ceil((hi[k] - lo[k] + 2 * margin) / cell_)));
  const size_t cells = size_t(size_[0]) * size_[1] * size_[2];
  std::vector<std::vector<int>> buckets(cells);
  for (size_t t = 0; t < triangles_.size(); ++t) {
    Eigen::Vector3d tlo = vertices_[triangles_[t][0]], thi = tlo;
    for (int k = 1; k < 3; ++k) {
      tlo = tlo.cwiseMin(vertices_[triangles_[t][k]]);
      thi = thi.cwiseMax(vertices_[triangles_[t][k]]);
    }
    Eigen::Vector3i a, b;
    for (int k = 0; k < 3; ++k) {
      a[k] = std::clamp(static_cast<int>((tlo[k] - origin_[k]) / cell_), 0, size_[k] - 1);
      b[k] = std::clamp(static_cast<int>((thi[k] - origin_[k]) / cell_), 0, size_[k] - 1);
    }
    for (int z = a.z(); z <= b.z(); ++z)
      for (int y = a.y(); y <= b.y(); ++y)
        for (int x = a.x(); x <= b.x(); ++x)
          buckets[(size_t(z) * size_[1] + y) * size_[0] + x].push_back(static_cast<int>(t));
  }
  cell_start_.assign(cells + 1, 0);
  for (size_t c = 0; c < cells; ++c) {
    cell_start_[c + 1] = cell_start_[c] + static_cast<int>(buckets[c].size());
    cell_triangles_.insert(cell_triangles_.end(), buckets[c].begin(), buckets[c].end());
  }
  stamp_.assign(triangles_.size(), 0);
}

double SurfaceDistance::toTriangle(const Eigen::Vector3d& p, int t) const {
  const Eigen::Vector3i& f = triangles_[t];
  return (closestOnTriangle(p, vertices_[f[0]], vertices_[f[1]], vertices_[f[2]]) - p).norm();
}

double SurfaceDistance::bruteForce(const Eigen::Vector3d& p) const {
  double best = std::numeric_limits<double>::infinity();
  for (size_t t = 0; t < triangles_.size(); ++t) best = std::min(best, toTriangle(p, int(t)));
  return best;
}

double SurfaceDistance::distance(const Eigen::Vector3d& p) const {
  Eigen::Vector3i c;
  for (int k = 0; k < 3; ++k) {
    const double u = (p[k] - origin_[k]) / cell_;
    if (!(u >= 0 && u < size_[k])) return bruteForce(p);  // far from the surface: rare
    c[k] = static_cast<int>(u);
  }
  if (++stamp_now_ == 0) std::fill(stamp_.begin(), stamp_.end(), 0), stamp_now_ = 1;
  double best = std::numeric_limits<double>::infinity();
  const int max_ring = std::max({size_[0], size_[1], size_[2]});
  for (int ring = 0; ring <= max_ring; ++ring) {
    // The cells at Chebyshev distance `ring` from p's cell.
    for (int z = c.z() - ring; z <= c.z() + ring; ++z) {
      if (z < 0 || z >= size_[2]) continue;
      for (int y = c.y() - ring; y <= c.y() + ring; ++y) {
        if (y < 0 || y >= size_[1]) continue;
        for (int x = c.x() - ring; x <= c.x() + ring; ++x) {
          if (x < 0 || x >= size_[0]) continue;
          if (std::max({std::abs(x - c.x()), std::abs(y - c.y()), std::abs(z - c.z())}) != ring)
            continue;
          const size_t cell = (size_t(z) * size_[1] + y) * size_[0] + x;
          for (int i = cell_start_[cell]; i < cell_start_[cell + 1]; ++i) {
            const int t = cell_triangles_[i];
            if (stamp_[t] == stamp_now_) continue;
            stamp_[t] = stamp_now_;
            best = std::min(best, toTriangle(p, t));
          }
        }
      }
    }
    // Every cell within `ring` is searched: anything unsearched is at least ring cells away.
    if (best <= ring * cell_) break;
  }
  return best;
}

void surfaceDistancesMm(const Eigen::Matrix3Xf& points, const SurfaceDistance& surface,
                        std::vector<double>& out) {
  out.resize(points.cols());
  for (Eigen::Index v = 0; v < points.cols(); ++v)
    out[v] = 1000.0 * surface.distance(points.col(v).cast<double>());
}

void nearestOffsetsAlongNormals(const Eigen::Matrix3Xf& positions, const Eigen::Matrix3Xf& normals,
                                const SurfaceDistance& surface, double t_inward_m, double t_max_m,
                                double step_m, Eigen::Matrix3Xf& out) {
  if (out.cols() != positions.cols()) out.resize(3, positions.cols());
  const int inward = step_m > 0 ? int(std::floor(t_inward_m / step_m + 1e-9)) : 0;
  const int outward = step_m > 0 ? int(std::floor(t_max_m / step_m + 1e-9)) : 0;
  for (Eigen::Index v = 0; v < positions.cols(); ++v) {
    const Eigen::Vector3d p = positions.col(v).cast<double>(), n = normals.col(v).cast<double>();
    double nearest = std::numeric_limits<double>::infinity(), best_t = 0;
    for (int k = -inward; k <= outward; ++k) {
      const double t = k * step_m, d = surface.distance(p + t * n);
      // Ties (a line along the surface) go to the smaller offset.
      if (d < nearest || (d == nearest && std::abs(t) < std::abs(best_t))) nearest = d, best_t = t;
    }
    out.col(v) = (p + best_t * n).cast<float>();
  }
}

SurfaceError poolSurfaceErrors(const std::vector<std::vector<double>>& distances_mm) {
  std::vector<double> all;
  for (const std::vector<double>& d : distances_mm) all.insert(all.end(), d.begin(), d.end());
  SurfaceError e;
  e.points = static_cast<int>(all.size());
  if (all.empty()) return e;
  double sum = 0;
  for (double d : all) sum += d;
  e.mean_mm = sum / double(all.size());
  e.max_mm = *std::max_element(all.begin(), all.end());
  e.p95_mm = nearestRankPercentile(all, 0.95);
  return e;
}

SurfaceError surfaceError(const Eigen::Matrix3Xf& points, const SurfaceDistance& surface) {
  std::vector<double> d;
  surfaceDistancesMm(points, surface, d);
  return poolSurfaceErrors({d});
}

SurfaceEvaluation evaluateSurface(const std::filesystem::path& folder, const SkinnedMesh& generic,
                                  const SurfaceEvaluationOptions& options) {
  const SessionReader session(folder);
  if (!session.hasTruth())
    throw Error(folder.string() + ": the session has no truth (not from the virtual studio)");
  std::vector<std::string> names;
  const std::vector<std::vector<Eigen::Vector3d>> truth_joints = session.readTruthJoints(&names);
  const Skeleton& skeleton = generic.skeleton;
  // The generic skeleton's joints among the truth's columns, by name.
  std::vector<int> column(skeleton.jointCount(), -1);
  for (int j = 0; j < skeleton.jointCount(); ++j) {
    for (size_t k = 0; k < names.size(); ++k)
      if (names[k] == skeleton.joint(j).name) column[j] = static_cast<int>(k);
    if (column[j] < 0)
      throw Error(folder.string() + ": truth/joints.csv has no joint '" + skeleton.joint(j).name +
                  "' of the generic skeleton");
  }
  const Rig& rig = session.rig();
  const RefineConfig& config = options.refine;
  FrameRefiner refiner(rig, config, generic.rest.vertexCount(), generic.rest.triangles);
  refiner.setPlates(platesOf(session, options.plates));
  std::vector<CameraFrame> frames;
  std::vector<uint8_t> previous;
  double change_sum = 0;
  int changes = 0;
  Eigen::Matrix3Xf positions, normals, refined;
  std::vector<std::vector<double>> before, after;
  std::vector<double> d;
  std::vector<Eigen::Vector3d> targets(skeleton.jointCount());
  JointPoseFit fit;
  bool first = true;
  double fit_rms = 0, bytes = 0;
  SurfaceEvaluation result;

  const int step = std::max(1, options.frame_step);
  for (int i = options.first_frame; i < session.frameCount(); i += step) {
    if (options.max_frames > 0 && result.frames >= options.max_frames) break;
    for (int j = 0; j < skeleton.jointCount(); ++j) targets[j] = truth_joints[i][column[j]];
    fit = fitPoseToJoints(skeleton, targets, first ? initialJointPoseFit(skeleton, targets) : fit);
    fit_rms += fit.rms_m;
    posedScaledMesh(generic, fit, positions, normals);

    session.readFrame(i, frames);
    first = false;
    refiner.refine(frames, positions, normals, refined);
    bytes += double(refiner.lastWireBytes());
    const std::vector<uint8_t>& offsets = refiner.offsets();
    if (!previous.empty()) {
      double change = 0;
      for (size_t v = 0; v < offsets.size(); ++v)
        change += std::abs(config.levelOffset(offsets[v]) - config.levelOffset(previous[v]));
      change_sum += 1000.0 * change / double(offsets.size());
      ++changes;
    }
    previous = offsets;

    const TriangleMesh truth =
        readPlyMesh(folder / "truth" / "surface" / fmt::format("{:06}.ply", session.frameId(i)));
    const SurfaceDistance surface(truth);
    surfaceDistancesMm(positions, surface, d);
    before.push_back(d);
    result.unrefined_per_frame.push_back(poolSurfaceErrors({d}));
    surfaceDistancesMm(refined, surface, d);
    after.push_back(d);
    result.refined_per_frame.push_back(poolSurfaceErrors({d}));
    ++result.frames;
  }
  if (result.frames == 0) throw Error(folder.string() + ": no frames to evaluate");
  result.unrefined = poolSurfaceErrors(before);
  result.refined = poolSurfaceErrors(after);
  result.joint_fit_rms_mm = 1000.0 * fit_rms / result.frames;
  result.offset_change_mm = changes > 0 ? change_sum / changes : std::nan("");  // one frame: none
  result.statistics_bytes_per_node = bytes / (double(result.frames) * rig.nodeCount());
  return result;
}

}  // namespace lumistage
