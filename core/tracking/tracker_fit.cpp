// The tracker's fit (PoseTracker::Impl, pose_tracker_impl.h): the cost of a pose against the hull's
// samples and the silhouettes, with its analytic normal equations, and Levenberg-Marquardt over
// it; the capsules placed for a pose and each hull sample's nearest one.
#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/tracking/pose_tracker_impl.h"

namespace lumistage {

using namespace tracker_detail;

double PoseTracker::Impl::evaluate(const Pose& p, bool jacobian, Eigen::MatrixXd& h,
                                   Eigen::VectorXd& grad) {
  // The cost's terms in turn: the hull's samples, the rim's rays, the bones' axes inside every
  // silhouette, the parts kept apart (each adding its residuals' normal equations per joint, when
  // `jacobian`), the joints' sums into the degrees of freedom, then the temporal prior.
  skeleton.forwardKinematics(p, global);
  if (jacobian) {
    h.setZero();
    grad.setZero();
    prepareJacobian(p);
  }
  placeCapsules();
  double cost = 0;
  addHullCost(jacobian, cost);
  addRimCost(jacobian, cost);
  addSilhouetteCost(jacobian, cost);
  addApartCost(jacobian, cost);
  if (jacobian) sumIntoDofs(h, grad);
  if (use_prior) addPriorCost(p, jacobian, h, grad, cost);
  if (jacobian) h.triangularView<Eigen::StrictlyLower>() = h.transpose();
  return cost;
}

double PoseTracker::Impl::score(const Pose& p, double bound) {
  skeleton.forwardKinematics(p, global);
  capsuleEnds(cap_a, cap_b);
  double cost = 0;
  // Checked every kChunk samples (on the reference walk about half the hypotheses are given up,
  // after two thirds of the hull on average).
  constexpr size_t kChunk = 32;
  capsuleSpheres();
  int hint = 0;
  for (size_t i = 0; i < hull.size(); ++i) {
    cost += hullTerm(hullDistances(hull[i], hint, 0));
    if (i % kChunk == kChunk - 1 && cost > bound) return cost;
  }
  if (opt.rim_weight > 0) {
    for (const RimRay& ray : rim) {
      if (!present[ray.camera]) continue;
      const double best = rimDistances(ray);
      if (best <= opt.rim_outlier_m) cost += rimTerm(best);
    }
  }
  if (cost > bound) return cost;
  addSilhouetteCost(false, cost);
  addApartCost(false, cost);
  return cost;
}

void PoseTracker::Impl::prepareJacobian(const Pose& p) {
  const int n = int(dofs.size());
  for (int d = 0; d < n; ++d) {
    const Dof& dof = dofs[d];
    if (dof.kind == Dof::kTranslation) {
      dof_axis[d] = Eigen::Vector3d::Unit(dof.axis);
    } else if (dof.kind == Dof::kRootRotation) {
      dof_axis[d] = Eigen::Vector3d::Unit(dof.axis);
      dof_centre[d] = global[0].translation();
    } else {
      const Eigen::Matrix3d rp = global[skeleton.joint(dof.joint).parent].linear();
      const Eigen::Vector3d& a = p.angles_rad[dof.joint];
      if (dof.axis == 0) {
        dof_axis[d] = rp.col(0);
      } else if (dof.axis == 1) {
        dof_axis[d] =
            rp * Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX()) * Eigen::Vector3d::UnitY();
      } else {
        dof_axis[d] = rp * Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX()) *
                      Eigen::AngleAxisd(a.y(), Eigen::Vector3d::UnitY()) * Eigen::Vector3d::UnitZ();
      }
      dof_centre[d] = global[dof.joint].translation();
    }
    if (dof.kind == Dof::kTranslation) {
      dof_spatial[d] << dof_axis[d], Eigen::Vector3d::Zero();
    } else {
      dof_spatial[d] << dof_centre[d].cross(dof_axis[d]), dof_axis[d];
    }
  }
  for (size_t j = 0; j < joint_m.size(); ++j) {
    joint_m[j].setZero();
    joint_g[j].setZero();
    joint_used[j] = 0;
  }
}

void PoseTracker::Impl::addHullCost(bool jacobian, double& cost) {
  // Hull surface samples on the model's surface.
  const double delta_out = opt.huber_m, delta_in = 4 * opt.huber_m;
  for (size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector3d& v = hull[i];
    double best;
    Eigen::Vector3d best_closest;
    const int best_c = nearestCapsule(i, best, best_closest);
    // The hull holds the body: a model surface beyond the hull (r < 0) is wrong, a hull beyond
    // the model (r > 0) may be a phantom of the carving (between the legs, under the arms).
    const double r = best, ar = std::abs(r);
    const double delta = r < 0 ? delta_in : delta_out;
    cost += hullTerm(r);
    if (jacobian) {
      const Eigen::Vector3d diff = v - best_closest;
      const double len = diff.norm();
      if (len < 1e-9 || best_c < 0) continue;
      const double w = ar <= delta ? 1.0 : delta / ar;
      accumulate(capsules[best_c].joint, best_closest, -diff / len, r, w);
    }
  }
}

void PoseTracker::Impl::addRimCost(bool jacobian, double& cost) {
  // Rays through the silhouettes' edges touching the body's surface.
  if (opt.rim_weight > 0) {
    const double delta = opt.rim_huber_m, wr = opt.rim_weight;
    for (size_t i = 0; i < rim.size(); ++i) {
      const RimRay& ray = rim[i];
      if (!present[ray.camera]) continue;
      Eigen::Vector3d on_ray, on_segment;
      double best;
      const int best_c = nearestRimCapsule(i, best, on_ray, on_segment);
      if (best_c < 0 || best > opt.rim_outlier_m) continue;  // no body part near: not the actor's
      const double ar = std::abs(best);
      cost += rimTerm(best);
      if (!jacobian) continue;
      const Eigen::Vector3d diff = on_segment - on_ray;
      const double len = diff.norm();
      if (len < 1e-9) continue;
      accumulate(capsules[best_c].joint, on_segment, diff / len, best,
                 wr * (ar <= delta ? 1.0 : delta / ar));
    }
  }
}

void PoseTracker::Impl::addSilhouetteCost(bool jacobian, double& cost) {
  // Axis samples inside every silhouette.
  const double ws = opt.silhouette_weight;
  const int step = opt.silhouette_step;
  for (const Sample& s : samples) {
    const Eigen::Vector3d q = global[s.joint] * s.local;
    for (int c = 0; c < cameras; ++c) {
      if (!present[c]) continue;
      const Camera& cam = rig.camera(c);
      const Eigen::Vector3d x = cam.toCamera(q);
      if (x.z() <= 0.1) continue;
      const auto pix = cam.project(q);
      if (!pix) continue;
      const double cx = ((*pix)(0) - step / 2) / step, cy = ((*pix)(1) - step / 2) / step;
      const int w = cell_w[c], hgt = cell_h[c];
      if (cx < 0 || cy < 0 || cx > w - 1 || cy > hgt - 1) continue;
      const int x0 = std::min(int(cx), w - 2), y0 = std::min(int(cy), hgt - 2);
      const double fx = cx - x0, fy = cy - y0;
      const Eigen::Array4i& box = dt_box[c];
      double value, gx, gy;
      if (x0 >= box[0] && x0 + 1 <= box[2] && y0 >= box[1] && y0 + 1 <= box[3]) {
        const float* d = &dt[c][size_t(y0) * w + x0];
        const double d00 = d[0], d10 = d[1], d01 = d[w], d11 = d[w + 1];
        value = (1 - fy) * ((1 - fx) * d00 + fx * d10) + fy * ((1 - fx) * d01 + fx * d11);
        gx = (1 - fy) * (d10 - d00) + fy * (d11 - d01);
        gy = (1 - fx) * (d01 - d00) + fx * (d11 - d10);
      } else if (box[2] < box[0]) {
        continue;  // no silhouette in this view: nothing to be drawn toward
      } else {
        // Beyond the transform's box: its nearest cell's distance plus the way to it (the
        // silhouette is at least kDtMargin cells further).
        const double px = std::clamp(cx, double(box[0]), double(box[2])),
                     py = std::clamp(cy, double(box[1]), double(box[3]));
        const double ex = cx - px, ey = cy - py, e = std::hypot(ex, ey);
        value = dt[c][size_t(std::lround(py)) * w + size_t(std::lround(px))] + e;
        gx = e > 0 ? ex / e : 0;
        gy = e > 0 ? ey / e : 0;
      }
      if (value <= 0) continue;
      const double m_per_cell = step * x.z() / cam.intrinsics().fx;
      const double r = value * m_per_cell;
      cost += 0.5 * ws * r * r;
      if (!jacobian) continue;
      const Intrinsics& k = cam.intrinsics();
      const double iz = 1.0 / x.z();
      // d(cell)/d(camera coordinates), pinhole (the lens distortion is left out of the slope).
      const Eigen::Vector3d du(k.fx * iz, 0, -k.fx * x.x() * iz * iz),
          dv(0, k.fy * iz, -k.fy * x.y() * iz * iz);
      const Eigen::Vector3d dr_dx = m_per_cell / step * (gx * du + gy * dv);
      accumulate(s.joint, q, cam.rotation().transpose() * dr_dx, r, ws);
    }
  }
}

void PoseTracker::Impl::addApartCost(bool jacobian, double& cost) {
  // Parts of the body kept apart. Each overlap moves with two joints: its slope goes to both, and
  // the normal equations leave out the products between their chains (Levenberg-Marquardt takes
  // a step only where the cost falls, so an approximate J^T J does).
  if (opt.apart_weight > 0) {
    const double w = opt.apart_weight;
    Eigen::Vector3d on_a, on_b;
    for (const auto& [a, b] : apart) {
      const double d = segmentSegmentDistance(cap_a[a], cap_b[a], cap_a[b], cap_b[b], on_a, on_b);
      const double r = opt.apart_fraction * (capsules[a].radius_m + capsules[b].radius_m) - d;
      if (r <= 0) continue;
      cost += 0.5 * w * r * r;
      if (!jacobian || d < 1e-9) continue;
      const Eigen::Vector3d n = (on_a - on_b) / d;
      accumulate(capsules[a].joint, on_a, -n, r, w);
      accumulate(capsules[b].joint, on_b, n, r, w);
    }
  }
}

void PoseTracker::Impl::sumIntoDofs(Eigen::MatrixXd& h, Eigen::VectorXd& grad) const {
  for (size_t j = 0; j < joint_m.size(); ++j) {
    if (!joint_used[j]) continue;
    const std::vector<int>& ch = chain[j];
    for (size_t b = 0; b < ch.size(); ++b) {
      const Vector6d moved = joint_m[j] * dof_spatial[ch[b]];
      for (size_t a = 0; a <= b; ++a) h(ch[a], ch[b]) += dof_spatial[ch[a]].dot(moved);
      grad(ch[b]) += dof_spatial[ch[b]].dot(joint_g[j]);
    }
  }
}

void PoseTracker::Impl::addPriorCost(const Pose& p, bool jacobian, Eigen::MatrixXd& h,
                                     Eigen::VectorXd& grad, double& cost) const {
  const int n = int(dofs.size());
  const double w = prior_weight;
  Eigen::Vector3d e = p.root_translation_m - prior_pose.root_translation_m;
  const Eigen::Matrix3d r_now = global[0].linear();
  const Eigen::Matrix3d r_prior = rotationFromVector(prior_pose.angles_rad[0]);
  const Eigen::AngleAxisd rot(r_now * r_prior.transpose());
  const Eigen::Vector3d er = rot.angle() * rot.axis();
  cost += 0.5 * w * (e.squaredNorm() + er.squaredNorm());
  for (int d = 0; d < n; ++d) {
    const Dof& dof = dofs[d];
    double err;
    if (dof.kind == Dof::kTranslation) {
      err = e[dof.axis];
    } else if (dof.kind == Dof::kRootRotation) {
      err = er[dof.axis];
    } else {
      err = p.angles_rad[dof.joint][dof.axis] - prior_pose.angles_rad[dof.joint][dof.axis];
      cost += 0.5 * w * err * err;
    }
    if (jacobian) {
      h(d, d) += w;
      grad(d) += w * err;
    }
  }
}

void PoseTracker::Impl::apply(Pose& p, const Eigen::VectorXd& delta) const {
  for (size_t d = 0; d < dofs.size(); ++d) {
    const Dof& dof = dofs[d];
    if (dof.kind == Dof::kTranslation) {
      p.root_translation_m[dof.axis] += delta(d);
    } else if (dof.kind == Dof::kEuler) {
      p.angles_rad[dof.joint][dof.axis] += delta(d);
    }
  }
  const Eigen::Vector3d w = delta.segment<3>(3);
  if (w.norm() > 0) {
    const Eigen::Matrix3d r0 = rotationFromVector(p.angles_rad[0]);
    const Eigen::AngleAxisd r(Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix() * r0);
    p.angles_rad[0] = r.angle() * r.axis();
  }
  skeleton.clampToLimits(p);
}

double PoseTracker::Impl::fit(Pose& p, int iterations) {
  double cost = evaluate(p, true, H, g);
  double lambda = 1e-3;
  for (int it = 0; it < iterations; ++it) {
    damped = H;
    for (int d = 0; d < damped.rows(); ++d) damped(d, d) += lambda * H(d, d) + 1e-6;
    delta = g;
    // Degrees of freedom held: their rows and columns out of the system, their step zero.
    for (int d = 0; d < int(dof_held.size()); ++d) {
      if (!dof_held[d]) continue;
      damped.row(d).setZero();
      damped.col(d).setZero();
      damped(d, d) = 1;
      delta(d) = 0;
    }
    ldlt.compute(damped);
    ldlt.solveInPlace(delta);
    delta = -delta;
    candidate = p;
    apply(candidate, delta);
    const double c = evaluate(candidate, true, H_new, g_new);
    if (c < cost) {
      const double gain = cost - c;
      p = candidate;
      cost = c;
      std::swap(H, H_new);
      std::swap(g, g_new);
      lambda = std::max(1e-6, lambda / 3);
      if (gain < 1e-7 * std::max(1.0, cost)) break;
    } else {
      lambda *= 8;
      if (lambda > 1e4) break;
    }
  }
  return cost;
}

void PoseTracker::Impl::capsuleEnds(std::vector<Eigen::Vector3d>& a,
                                    std::vector<Eigen::Vector3d>& b) const {
  const size_t n = capsules.size();
  a.resize(n);
  b.resize(n);
  for (size_t c = 0; c < n; ++c) {
    const Eigen::Isometry3d& t = global[capsules[c].joint];
    a[c] = t * capsules[c].a;
    b[c] = t * capsules[c].b;
  }
}

void PoseTracker::Impl::capsuleSpheres() {
  const size_t n = capsules.size();
  cap_mid.resize(n);
  cap_reach.resize(n);
  for (size_t c = 0; c < n; ++c) {
    cap_mid[c] = 0.5 * (cap_a[c] + cap_b[c]);
    cap_reach[c] = 0.5 * (cap_b[c] - cap_a[c]).norm() + capsules[c].radius_m;
  }
}

double PoseTracker::Impl::hullDistances(const Eigen::Vector3d& x, int& hint, double margin) {
  const size_t n = capsules.size();
  capsule_distance.resize(n);
  Eigen::Vector3d point;
  // Beyond its sphere by more than the nearest so far and the margin: a capsule's surface is at
  // least that far (its axis lies within half its length of the middle).
  double best = segmentDistance(x, cap_a[hint], cap_b[hint], point) - capsules[hint].radius_m;
  capsule_distance[hint] = best;
  int nearest = hint;
  for (size_t c = 0; c < n; ++c) {
    if (int(c) == hint) continue;
    const double reach = best + margin + cap_reach[c];
    if (reach < 0 || (x - cap_mid[c]).squaredNorm() > reach * reach) {
      capsule_distance[c] = std::numeric_limits<double>::infinity();
      continue;
    }
    const double d = segmentDistance(x, cap_a[c], cap_b[c], point) - capsules[c].radius_m;
    capsule_distance[c] = d;
    if (d < best) best = d, nearest = int(c);
  }
  hint = nearest;
  return best;
}

double PoseTracker::Impl::rimDistances(const RimRay& ray) {
  const size_t n = capsules.size();
  capsule_distance.resize(n);
  Eigen::Vector3d on_ray, on_segment;
  double best = 1e9;
  for (size_t c = 0; c < n; ++c) {
    capsule_distance[c] =
        raySegmentDistance(ray.origin, ray.direction, cap_a[c], cap_b[c], on_ray, on_segment) -
        capsules[c].radius_m;
    best = std::min(best, capsule_distance[c]);
  }
  return best;
}

void PoseTracker::Impl::placeCapsules() {
  const size_t n = capsules.size();
  capsuleEnds(cap_a, cap_b);
  double moved = 0;
  if (candidates_valid) {
    for (size_t c = 0; c < n; ++c) {
      moved = std::max(moved, (cap_a[c] - candidate_a[c]).squaredNorm());
      moved = std::max(moved, (cap_b[c] - candidate_b[c]).squaredNorm());
    }
  }
  if (candidates_valid && std::sqrt(moved) <= 0.5 * kCandidateMargin) return;
  candidate_a = cap_a;
  candidate_b = cap_b;
  // Each hull sample's and rim ray's capsules within kCandidateMargin of its nearest.
  capsuleSpheres();
  candidates.clear();
  candidate_begin.resize(hull.size() + 1);
  // The capsules in capsule_distance within kCandidateMargin of `best`, onto `list`.
  const auto appendNear = [&](double best, std::vector<uint8_t>& list) {
    for (size_t c = 0; c < n; ++c)
      if (capsule_distance[c] <= best + kCandidateMargin) list.push_back(uint8_t(c));
  };
  int hint = 0;
  for (size_t i = 0; i < hull.size(); ++i) {
    candidate_begin[i] = int(candidates.size());
    appendNear(hullDistances(hull[i], hint, kCandidateMargin), candidates);
  }
  candidate_begin[hull.size()] = int(candidates.size());
  rim_candidates.clear();
  rim_candidate_begin.resize(rim.size() + 1);
  for (size_t i = 0; i < rim.size(); ++i) {
    rim_candidate_begin[i] = int(rim_candidates.size());
    appendNear(rimDistances(rim[i]), rim_candidates);
  }
  rim_candidate_begin[rim.size()] = int(rim_candidates.size());
  candidates_valid = true;
}

int PoseTracker::Impl::nearestRimCapsule(size_t i, double& distance, Eigen::Vector3d& on_ray,
                                         Eigen::Vector3d& on_segment) const {
  distance = 1e9;
  on_ray = on_segment = Eigen::Vector3d::Zero();
  int best = -1;
  Eigen::Vector3d r, q;
  for (int k = rim_candidate_begin[i]; k < rim_candidate_begin[i + 1]; ++k) {
    const int c = rim_candidates[k];
    const double d = raySegmentDistance(rim[i].origin, rim[i].direction, cap_a[c], cap_b[c], r, q) -
                     capsules[c].radius_m;
    if (d < distance) distance = d, best = c, on_ray = r, on_segment = q;
  }
  return best;
}

int PoseTracker::Impl::nearestCapsule(size_t i, double& distance, Eigen::Vector3d& closest) const {
  distance = 1e9;
  closest = Eigen::Vector3d::Zero();
  int best = -1;
  for (int k = candidate_begin[i]; k < candidate_begin[i + 1]; ++k) {
    const int c = candidates[k];
    Eigen::Vector3d point;
    const double d = segmentDistance(hull[i], cap_a[c], cap_b[c], point) - capsules[c].radius_m;
    if (d < distance) distance = d, best = c, closest = point;
  }
  return best;
}

double PoseTracker::Impl::rimRms(const Pose& p) {
  skeleton.forwardKinematics(p, global);
  placeCapsules();
  rim_residuals.clear();
  Eigen::Vector3d on_ray, on_segment;
  for (size_t i = 0; i < rim.size(); ++i) {
    if (!present[rim[i].camera]) continue;
    double best;
    nearestRimCapsule(i, best, on_ray, on_segment);
    rim_residuals.push_back(std::min(std::abs(best), opt.rim_outlier_m));
  }
  if (rim_residuals.empty()) return 1.0;
  // The best kRimTrim of them: a segmenter's mask that takes a bag or a shadow in with the actor
  // is no worse a fit.
  constexpr double kRimTrim = 0.8;
  const size_t kept = std::max<size_t>(1, size_t(kRimTrim * double(rim_residuals.size())));
  std::nth_element(rim_residuals.begin(), rim_residuals.begin() + (kept - 1), rim_residuals.end());
  double sum = 0;
  for (size_t i = 0; i < kept; ++i) sum += rim_residuals[i] * rim_residuals[i];
  return std::sqrt(sum / double(kept));
}

double PoseTracker::Impl::fitRms(const Pose& p) {
  skeleton.forwardKinematics(p, global);
  placeCapsules();
  double sum = 0;
  for (size_t i = 0; i < hull.size(); ++i) {
    double best;
    Eigen::Vector3d closest;
    nearestCapsule(i, best, closest);
    best = std::min(std::abs(best), 0.2);
    sum += best * best;
  }
  return hull.empty() ? 1.0 : std::sqrt(sum / hull.size());
}

}  // namespace lumistage
