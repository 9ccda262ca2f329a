#include "core/tracking/pose_tracker.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/geometry/stage_volume.h"
#include "core/tracking/pose_tracker_impl.h"

namespace lumistage {

using namespace tracker_detail;

PoseTracker::Impl::Impl(const Rig& r, const SkinnedMesh& mesh, const PoseTrackerOptions& o)
    : opt(o), rig(r), cameras(r.cameraCount()), generic(mesh.skeleton) {
  checkHumanJointOrder(generic, "PoseTracker: the generic skeleton");
  const int step = opt.silhouette_step;
  for (int c = 0; c < cameras; ++c) {
    cell_w.push_back(rig.camera(c).width() / step);
    cell_h.push_back(rig.camera(c).height() / step);
  }
  const bool wide = *std::max_element(cell_w.begin(), cell_w.end()) *
                        int64_t(*std::max_element(cell_h.begin(), cell_h.end())) >=
                    kUnseen<uint16_t>;
  sizeStage(wide);
  projectVoxels(wide);
  dt.resize(cameras);
  for (int c = 0; c < cameras; ++c) dt[c].assign(size_t(cell_w[c]) * cell_h[c], kFarCells);
  dt_box.assign(cameras, Eigen::Array4i(0, 0, -1, -1));
  present.assign(cameras, 0);
  told_empty.assign(cameras, 0);
  const int longest = std::max(*std::max_element(cell_w.begin(), cell_w.end()),
                               *std::max_element(cell_h.begin(), cell_h.end()));
  dt_f.resize(longest);
  dt_d.resize(longest);
  dt_z.resize(longest + 1);
  dt_v.resize(longest);
  dt_col.resize(longest);

  buildModel(mesh);
  makeDofs();
  pose = previous = prior_pose = candidate = predicted = fitted = Pose::rest(generic.jointCount());
  surface_all.reserve(occupied.size() / 16);
  hull.reserve(opt.max_hull_points + 1);
}

void PoseTracker::Impl::sizeStage(bool wide) {
  stage = opt.stage ? *opt.stage : stageVolume(rig);
  const auto tableBytes = [&](const StageBox& box) {
    const Eigen::Vector3i d = (box.size() / opt.voxel_m).array().ceil().cast<int>();
    const Eigen::Vector3i blocks = blocksOf(d);
    // The voxels' cells, and the blocks' cell and reach (makeBlocks).
    return size_t(d.x()) * d.y() * d.z() * cameras * (wide ? 4 : 2) +
           size_t(blocks.x()) * blocks.y() * blocks.z() * cameras * 5;
  };
  // A box worked out from the cameras (none given) is narrowed about its centre, down to the
  // default floor, until its tables fit: many cameras of a megapixel and more on a wide floor
  // would pass max_table_bytes where the old 3 x 3 m box did not.
  const bool from_cameras = opt.stage ? opt.stage_from_cameras : !rig.stage();
  if (from_cameras && tableBytes(stage) > opt.max_table_bytes) {
    const StageBox least;
    const StageBox covered = stage;
    while (tableBytes(stage) > opt.max_table_bytes &&
           (stage.size().x() > least.size().x() || stage.size().y() > least.size().y())) {
      for (int k = 0; k < 2; ++k) {
        if (stage.size()[k] <= least.size()[k]) continue;
        stage.lower[k] += 0.1, stage.upper[k] -= 0.1;
      }
    }
    spdlog::warn("stage: {} narrowed to {} so that the tracker's tables fit {} MB",
                 describeStage(covered), describeStage(stage), opt.max_table_bytes >> 20);
  }
  lower = stage.lower;
  dims = (stage.size() / opt.voxel_m).array().ceil().cast<int>();
  const size_t table_bytes = tableBytes(stage);
  if (table_bytes > opt.max_table_bytes) {
    throw std::invalid_argument(fmt::format(
        "the stage box ({}) at {} cm voxels needs {} MB of the tracker's tables for {} cameras, "
        "more than {} MB: give the rig file a smaller `stage` (docs/rig-file.md)",
        describeStage(stage), 100 * opt.voxel_m, table_bytes >> 20, cameras,
        opt.max_table_bytes >> 20));
  }
}

void PoseTracker::Impl::projectVoxels(bool wide) {
  const size_t voxels = size_t(dims.x()) * dims.y() * dims.z();
  const int step = opt.silhouette_step;
  if (wide) {
    cell_wide.assign(voxels * cameras, kUnseen<uint32_t>);
  } else {
    cell.assign(voxels * cameras, kUnseen<uint16_t>);
  }
  occupied.assign(voxels, 0);
  // Projects one z slab at a time (bounded temporary memory).
  const size_t slab = size_t(dims.x()) * dims.y();
  Eigen::Matrix3Xd centres(3, slab);
  Eigen::Matrix2Xd pixels;
  Eigen::VectorXd depths;
  for (int z = 0; z < dims.z(); ++z) {
    for (int y = 0; y < dims.y(); ++y) {
      for (int x = 0; x < dims.x(); ++x) {
        centres.col(size_t(y) * dims.x() + x) =
            lower + opt.voxel_m * Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5);
      }
    }
    for (int c = 0; c < cameras; ++c) {
      rig.camera(c).project(centres, pixels, depths);
      for (size_t i = 0; i < slab; ++i) {
        if (depths(i) <= 0) continue;
        const int x = int(std::floor(pixels(0, i) / step)),
                  y = int(std::floor(pixels(1, i) / step));
        if (x < 0 || y < 0 || x >= cell_w[c] || y >= cell_h[c]) continue;
        const size_t at = (size_t(z) * slab + i) * cameras + c;
        if (wide) {
          cell_wide[at] = uint32_t(y * cell_w[c] + x);
        } else {
          cell[at] = uint16_t(y * cell_w[c] + x);
        }
      }
    }
  }
  if (wide) {
    makeBlocks(cell_wide);
  } else {
    makeBlocks(cell);
  }
}

void PoseTracker::Impl::makeDofs() {
  // Degrees of freedom, parents first (so every chain is ascending).
  for (int k = 0; k < 3; ++k) dofs.push_back({Dof::kTranslation, 0, k});
  for (int k = 0; k < 3; ++k) dofs.push_back({Dof::kRootRotation, 0, k});
  chain.resize(generic.jointCount());
  for (int k = 0; k < 6; ++k) chain[0].push_back(k);
  for (int j = 1; j < generic.jointCount(); ++j) {
    chain[j] = chain[generic.joint(j).parent];
    const JointLimits& l = generic.joint(j).limits;
    // The clavicles stay at rest unless asked: the hull cannot see them, and free they soak up
    // the shoulders' misfit (raising the shoulders, lowering the neck).
    if (!opt.track_clavicles && (j == kRightClavicle || j == kLeftClavicle)) continue;
    for (int k = 0; k < 3; ++k) {
      if (l.upper_rad[k] > l.lower_rad[k]) {
        chain[j].push_back(int(dofs.size()));
        dofs.push_back({Dof::kEuler, j, k});
      }
    }
  }
  const int n = int(dofs.size());
  H.setZero(n, n);
  H_new.setZero(n, n);
  g.setZero(n);
  g_new.setZero(n);
  delta.setZero(n);
  damped.setZero(n, n);
  ldlt = Eigen::LDLT<Eigen::MatrixXd>(n);
  joint_m.resize(generic.jointCount());
  joint_g.resize(generic.jointCount());
  joint_used.resize(generic.jointCount());
  dof_spatial.resize(n);
  dof_axis.resize(n);
  dof_centre.resize(n);
}

namespace {

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const size_t k = size_t(q * double(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

}  // namespace

void PoseTracker::Impl::buildModel(const SkinnedMesh& mesh) {
  const Skeleton& s = generic;
  const auto& rest = s.restPositions();
  std::vector<std::vector<int>> children(s.jointCount());
  for (int j = 1; j < s.jointCount(); ++j) children[s.joint(j).parent].push_back(j);
  // Each joint's segments: to each child, or along its own bone for an end joint.
  std::vector<Capsule> segments;
  std::vector<std::vector<int>> of_joint(s.jointCount());
  auto segment = [&](const Capsule& c) -> Eigen::Vector3d {
    return c.child >= 0 ? Eigen::Vector3d(s.joint(c.child).offset_m) : c.end_dir;
  };
  for (int j = 0; j < s.jointCount(); ++j) {
    if (children[j].empty()) {
      Capsule c;
      c.joint = j;
      const Eigen::Vector3d off = s.joint(j).offset_m;
      c.end_dir = off.norm() > 0 ? Eigen::Vector3d(off.normalized()) : Eigen::Vector3d::UnitZ();
      of_joint[j].push_back(int(segments.size()));
      segments.push_back(c);
    } else {
      for (int child : children[j]) {
        Capsule c;
        c.joint = j;
        c.child = child;
        of_joint[j].push_back(int(segments.size()));
        segments.push_back(c);
      }
    }
  }
  // Vertices by their dominant joint, then by the nearest of its segments.
  std::vector<std::vector<Eigen::Vector3d>> verts(segments.size());
  for (int v = 0; v < mesh.rest.vertexCount(); ++v) {
    const auto& w = mesh.skin.weights[v];
    const int k = int(std::max_element(w.begin(), w.end()) - w.begin());
    const int j = mesh.skin.joints[v][k];
    const Eigen::Vector3d p = mesh.rest.positions.col(v).cast<double>() - rest[j];
    int best = -1;
    double best_d = 1e9;
    for (int ci : of_joint[j]) {
      Eigen::Vector3d closest;
      const Eigen::Vector3d seg =
          segments[ci].child >= 0 ? segment(segments[ci]) : Eigen::Vector3d(segment(segments[ci]));
      const double d = segmentDistance(p, Eigen::Vector3d::Zero(), seg, closest);
      if (d < best_d) best_d = d, best = ci;
    }
    if (best >= 0) verts[best].push_back(p);
  }
  for (size_t ci = 0; ci < segments.size(); ++ci) {
    const std::vector<Eigen::Vector3d>& pts = verts[ci];
    if (pts.size() < 8) continue;  // a segment no surface hangs on
    const Eigen::Vector3d seg = segment(segments[ci]);
    const double len = seg.norm();
    const Eigen::Vector3d u = seg / len;
    std::vector<double> t, dist, lat, depth;
    for (const Eigen::Vector3d& p : pts) {
      const double along = p.dot(u);
      const Eigen::Vector3d perp = p - along * u;
      t.push_back(along);
      dist.push_back(perp.norm());
      lat.push_back(std::abs(perp.x()));
      depth.push_back(std::abs(perp.y()));
    }
    const double t_lo = percentile(t, 0.03), t_hi = percentile(t, 0.97);
    // Wide and flat around a vertical segment (the torso): two capsules side by side.
    const double sx = percentile(lat, 0.9), sy = percentile(depth, 0.9);
    std::vector<double> offsets = {0.0};
    if (std::abs(u.z()) > 0.8 && sx > 1.3 * sy) offsets = {sx - sy, -(sx - sy)};
    double r = percentile(dist, 0.5);
    if (offsets.size() == 2) {
      std::vector<double> d2;
      for (const Eigen::Vector3d& p : pts) {
        const Eigen::Vector3d perp = p - p.dot(u) * u;
        const double o = perp.x() > 0 ? offsets[0] : offsets[1];
        d2.push_back((perp - Eigen::Vector3d(o, 0, 0)).norm());
      }
      r = percentile(d2, 0.5);
    }
    double a_t = t_lo + r, b_t = t_hi - r;
    if (a_t > b_t) a_t = b_t = 0.5 * (t_lo + t_hi);
    for (double o : offsets) {
      Capsule c = segments[ci];
      c.a_frac = a_t / len;
      c.b_frac = b_t / len;
      c.lateral_m = Eigen::Vector3d(o, 0, 0);
      c.generic_radius_m = r;
      capsules.push_back(c);
    }
  }
  generic_head_z = rest[kHead].z();
  generic_top_z = mesh.rest.positions.row(2).maxCoeff();
  generic_bottom_z = mesh.rest.positions.row(2).minCoeff();
  rest_pose = Pose::rest(generic.jointCount());
  cap_a.resize(capsules.size());
  cap_b.resize(capsules.size());
  setShape(BodyShape{});
  makeApartPairs();
  makeLibrary();
}

void PoseTracker::Impl::makeApartPairs() {
  // Which part each capsule is: 0 the torso and head, 1 / 2 the right / left arm (from the
  // shoulder), 3 / 4 the right / left leg (from the knee: the thighs meet at the crotch), -1 none
  // kept apart (the clavicles and the thighs).
  const auto part = [](int joint) {
    if (joint >= kRightShoulder && joint <= kRightHand) return 1;
    if (joint >= kLeftShoulder && joint <= kLeftHand) return 2;
    if (joint >= kRightKnee && joint <= kRightFoot) return 3;
    if (joint >= kLeftKnee && joint <= kLeftFoot) return 4;
    if (joint <= kHead) return 0;
    return -1;
  };
  std::vector<Eigen::Isometry3d> rest_global;
  skeleton.forwardKinematics(rest_pose, rest_global);
  apart.clear();
  for (int i = 0; i < int(capsules.size()); ++i) {
    for (int j = i + 1; j < int(capsules.size()); ++j) {
      const int pi = part(capsules[i].joint), pj = part(capsules[j].joint);
      if (pi < 0 || pj < 0 || pi == pj) continue;
      const bool arm_body = (pi == 0) != (pj == 0) && std::max(pi, pj) <= 2;
      const bool legs = std::min(pi, pj) == 3 && std::max(pi, pj) == 4;
      if (!arm_body && !legs) continue;
      Eigen::Vector3d on_a, on_b;
      const Eigen::Isometry3d &gi = rest_global[capsules[i].joint],
                              &gj = rest_global[capsules[j].joint];
      const double d = segmentSegmentDistance(gi * capsules[i].a, gi * capsules[i].b,
                                              gj * capsules[j].a, gj * capsules[j].b, on_a, on_b);
      // Touching at rest (an upper arm at the shoulder): no pair.
      if (d > capsules[i].radius_m + capsules[j].radius_m) apart.emplace_back(i, j);
    }
  }
}

void PoseTracker::Impl::setShape(const BodyShape& s) {
  candidates_valid = false;  // the capsules' radii change
  shape = s;
  skeleton = makeHumanSkeleton(s);
  const double scale = skeleton.restPositions()[kHead].z() / generic_head_z;
  samples.clear();
  for (Capsule& c : capsules) {
    Eigen::Vector3d seg;
    if (c.child >= 0) {
      seg = skeleton.joint(c.child).offset_m;
    } else {
      const double g = generic.joint(c.joint).offset_m.norm();
      const double ratio = g > 0 ? skeleton.joint(c.joint).offset_m.norm() / g : scale;
      seg = c.end_dir * ratio;
    }
    const Eigen::Vector3d lateral = c.lateral_m * scale * s.girth_scale;
    const bool foot = c.joint == kRightAnkle || c.joint == kLeftAnkle || c.joint == kRightFoot ||
                      c.joint == kLeftFoot;
    const double radius = c.generic_radius_m * scale * (foot ? foot_scale : 1.0);
    // The belly (a heavy actor's calibration) thickens the abdomen's capsules on top of the girth.
    const bool abdomen =
        c.joint == kSpine1 || c.joint == kSpine2 || (c.joint == kPelvis && c.child == kSpine1);
    c.radius_m = radius * s.girth_scale * (abdomen ? s.belly_scale : 1.0);
    // The girth thickens the body sideways (the clothes), not along its bones: the axis is
    // shortened at both ends by what the radius grew, so that the capsule reaches as far along
    // the bone as before. Lengthened with its radius instead, the capsules of the head and the
    // hands grew past the hull's ends, and the calibration (girth 1.23 for the clothed actor, 1.08
    // under the clothes) paid for it with the legs: 1.116 long for a 1.77 m actor, 1.086 and
    // 1.79 m now (the actor's: 1.04, 1.82 m). MPJPE 15.2 / 20.1 / 14.9 / 16.8 -> 14.8 / 18.4 /
    // 13.4 / 16.0 mm on the reference clips (docs/eval-report.md).
    const double len = seg.norm(), grow = c.radius_m - radius;
    double a_t = c.a_frac * len + grow, b_t = c.b_frac * len - grow;
    if (a_t > b_t) a_t = b_t = 0.5 * (c.a_frac + c.b_frac) * len;
    const Eigen::Vector3d u = len > 0 ? Eigen::Vector3d(seg / len) : Eigen::Vector3d::UnitZ();
    c.a = a_t * u + lateral;
    c.b = b_t * u + lateral;
    for (double t : {0.0, 0.5, 1.0}) samples.push_back({c.joint, c.a + t * (c.b - c.a)});
  }
  double bottom, top;
  modelExtent(rest_pose, bottom, top);
  rest_extent_m = top - bottom;
}

PoseTracker::PoseTracker(const Rig& rig, const SkinnedMesh& generic, PoseTrackerOptions options)
    : options_(options), impl_(new Impl(rig, generic, options)) {
  result_.pose = Pose::rest(kHumanJointCount);
}

PoseTracker::~PoseTracker() {
  delete impl_;
}

const StageBox& PoseTracker::stage() const {
  return impl_->stage;
}

const Skeleton& PoseTracker::skeleton() const {
  return impl_->skeleton;
}
const BodyShape& PoseTracker::shape() const {
  return impl_->shape;
}

void PoseTracker::setShape(const BodyShape& shape) {
  impl_->setShape(shape);
  impl_->shape_calibrated = true;
  impl_->shape_given = true;
  impl_->tracking = false;
}

bool PoseTracker::wantsColours() const {
  // Not tracking: the next frame initialises, and places the arms by them.
  return impl_->opt.arm_appearance && (!impl_->tracking || impl_->arms_pending);
}

void PoseTracker::reset() {
  impl_->tracking = false;
  impl_->forgetShape();
  impl_->bad_frames = 0;
  impl_->empty_frames = 0;
  impl_->shape_given = false;
  result_.state = TrackState::kNoActor;
}

const TrackResult& PoseTracker::track(const std::vector<const LowResSilhouette*>& silhouettes,
                                      const std::vector<const CellColours*>& colours) {
  Impl& m = *impl_;
  m.prepareSilhouettes(silhouettes);
  m.colours.assign(size_t(m.cameras), nullptr);
  for (const CellColours* c : colours)
    if (c && !c->rgb.empty() && c->camera >= 0 && c->camera < m.cameras &&
        m.present[size_t(c->camera)])
      m.colours[size_t(c->camera)] = c;
  result_.hull_points = 0;
  result_.left_out_camera = -1;
  double volume = 0;  // of the hull carved this frame, m³
  if (!m.tracking) {
    if (m.initialise(result_, volume)) {
      m.tracking = true;
      m.bad_frames = 0;
      result_.state = TrackState::kInitialised;
    } else {
      result_.state = TrackState::kNoActor;
    }
  } else {
    // Constant-velocity prediction, damped, as the starting point and the prior.
    Pose& predicted = m.predicted;
    if (m.has_previous) {
      m.predictFrom(m.pose, m.previous, predicted);
    } else {
      predicted = m.pose;
    }
    // Carve only around the predicted body, with the cameras that hold it.
    m.skeleton.forwardKinematics(predicted, m.global);
    result_.left_out_camera = m.leaveOutDisagreeingCamera();
    Eigen::Vector3d lo = m.global[0].translation(), hi = lo;
    for (const auto& t : m.global) {
      lo = lo.cwiseMin(t.translation());
      hi = hi.cwiseMax(t.translation());
    }
    const double margin = 0.35;
    lo -= Eigen::Vector3d::Constant(margin);
    hi += Eigen::Vector3d::Constant(margin);
    lo.z() = m.lower.z();
    const Eigen::Vector3i vlo = ((lo - m.lower) / m.opt.voxel_m).array().floor().cast<int>();
    const Eigen::Vector3i vhi = ((hi - m.lower) / m.opt.voxel_m).array().floor().cast<int>();
    double hull_top = 0, hull_bottom = 0;
    volume = m.carve(vlo, vhi, nullptr, &hull_top, &hull_bottom);
    // The rays through silhouettes' parts no voxel of this hull agrees with (a key's blotches)
    // are left out of the rim: no body explains them.
    m.dropRimRaysOffHull();
    result_.hull_points = int(m.hull.size());
    if (volume < m.opt.min_volume_m3 || volume > m.opt.max_volume_m3) {
      // No hull to fit (the actor gone, or one frame's keys broken: a light flickered, every mask
      // refused): a bad frame like a poor fit, the pose held, lost after lost_frames of them.
      if (++m.bad_frames >= m.opt.lost_frames) m.tracking = false;
      result_.state = TrackState::kLost;
    } else {
      m.use_prior = true;
      m.prior_pose = predicted;
      m.prior_weight = m.opt.prior_weight;
      Pose& p = m.fitted;
      p = predicted;
      m.fit(p, m.opt.iterations);
      // A limb left where the hull is not is tried where it is unexplained; after a try that
      // found nothing better, not again for kRecoveryWait frames (the carving's phantoms).
      constexpr int kRecoveryWait = 10;
      bool recovered = false;
      if (m.recovery_wait > 0) {
        --m.recovery_wait;
      } else if (const int rays = m.countUnexplained(p)) {
        recovered = m.recoverLimbs(p, rays, m.opt.iterations);
        if (!recovered) m.recovery_wait = kRecoveryWait;
      }
      m.use_prior = false;
      // Arms not yet placed by the cameras' colours since the actor was found (this frame is the
      // first with colours, or the turned twin took the pose's place): placed now.
      double arms_cost = 0;
      if (m.arms_pending && m.placeArmsWhenColoured(p, arms_cost)) recovered = true;
      result_.fit_rms_m = m.fitRms(p);
      result_.rim_rms_m = m.rimRms(p);
      // A recovered limb jumped: no velocity from it.
      m.previous = recovered ? p : m.pose;
      m.pose = p;
      m.has_previous = true;
      // In the first frames after an initialisation, its twin turned half round is tracked too.
      if (m.twin_frames > 0 && m.trackTwin(m.evaluate(m.pose, false, m.H, m.g))) {
        m.arms_pending = m.opt.arm_appearance;
        result_.fit_rms_m = m.fitRms(m.pose);
        result_.rim_rms_m = m.rimRms(m.pose);
      }
      if (!m.fitHolds(result_.fit_rms_m, result_.rim_rms_m)) {
        if (++m.bad_frames >= m.opt.lost_frames) m.tracking = false;
      } else {
        m.bad_frames = 0;
        if (m.opt.calibrate_shape && !m.shape_given) m.remeasureHeight(hull_bottom, hull_top);
      }
      result_.state = m.tracking ? TrackState::kTracking : TrackState::kLost;
    }
  }
  // The actor gone for good: whoever walks on next is calibrated anew (a given shape is kept).
  if (volume >= m.opt.min_volume_m3) {
    m.empty_frames = 0;
  } else if (++m.empty_frames == m.opt.forget_shape_after_empty_frames && m.shape_calibrated &&
             !m.shape_given) {
    spdlog::info(
        "tracker: the stage has been empty for {} frames: the next actor's proportions will be "
        "calibrated anew",
        m.empty_frames);
    m.forgetShape();
  }
  if (result_.valid()) {
    result_.pose = m.pose;
    m.skeleton.forwardKinematics(m.pose, m.global);
    result_.joints.resize(m.global.size());
    for (size_t j = 0; j < m.global.size(); ++j) result_.joints[j] = m.global[j].translation();
  }
  return result_;
}

}  // namespace lumistage
