// The tracker's limb recovery (PoseTracker::Impl, pose_tracker_impl.h): a limb that the fit left
// where the actor's is not (an arm down at the side while he holds both hands over his head) sits
// in a local minimum the fit cannot leave: the hull the arm should fill pulls toward the nearest
// capsule, not toward the arm. Hull that no capsule explains, within a limb's reach, is tried as
// where that limb is: the limb stretched toward its far end and the pose fitted again, kept when
// it explains the silhouettes better.
#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "core/tracking/pose_tracker_impl.h"

namespace lumistage {

using namespace tracker_detail;

namespace {

// A hull sample, or a ray through a silhouette's edge, this far from every capsule's surface is
// unexplained.
constexpr double kUnexplainedM = 0.10;
// Fewer unexplained samples (rays through the silhouettes' edges, hull samples) than this, or
// than this share of them: nothing to recover.
constexpr int kMinUnexplained = 12;
constexpr double kMinUnexplainedShare = 0.02;
// A recovered pose is kept when it lowers the fit's cost by this share.
constexpr double kMinGain = 0.03;
// A recovered pose is kept when it leaves at most this share of the silhouettes' edges unexplained
// that the pose found left.
constexpr double kKeptRays = 0.5;
// A limb whose end lies this near the unexplained hull it reaches for is where it should be.
constexpr double kNearM = 0.10;

}  // namespace

void PoseTracker::Impl::holdAllBut(const Limb& limb) {
  dof_held.assign(dofs.size(), 1);
  for (size_t d = 0; d < dofs.size(); ++d) {
    const int j = dofs[d].joint;
    if (j == limb.root || j == limb.middle || j == limb.end || j == limb.tip) dof_held[d] = 0;
  }
}

int PoseTracker::Impl::unexplainedRays() const {
  int count = 0;
  Eigen::Vector3d on_ray, on_segment;
  for (size_t i = 0; i < rim.size(); ++i) {
    if (!present[rim[i].camera]) continue;
    double distance;
    nearestRimCapsule(i, distance, on_ray, on_segment);
    if (distance > kUnexplainedM) ++count;
  }
  return count;
}

int PoseTracker::Impl::countUnexplained(const Pose& p) {
  skeleton.forwardKinematics(p, global);
  placeCapsules();
  // A limb missed shows in the silhouettes as edges that no body part comes near; the hull's
  // phantoms (between the legs, and large with few cameras) do not: the silhouettes' edges are
  // the body's.
  unexplained.clear();
  const int rays = unexplainedRays();
  if (rays < std::max(kMinUnexplained, int(std::lround(kMinUnexplainedShare * double(rim.size())))))
    return 0;
  for (size_t i = 0; i < hull.size(); ++i) {
    double distance;
    Eigen::Vector3d closest;
    nearestCapsule(i, distance, closest);
    if (distance > kUnexplainedM) unexplained.push_back(hull[i]);
  }
  const int least =
      std::max(kMinUnexplained, int(std::lround(kMinUnexplainedShare * double(hull.size()))));
  return int(unexplained.size()) >= least ? rays : 0;
}

bool PoseTracker::Impl::recoverLimbs(Pose& p, int rays, int iterations) {
  const bool prior = use_prior;
  use_prior = false;
  const double base = evaluate(p, false, H, g);
  limb_global = global;
  const auto& rest = skeleton.restPositions();
  Pose& best = limb_best;
  best = p;
  double best_cost = base;
  for (const Limb& limb : kLimbs) {
    // The unexplained samples the limb reaches, and toward the farthest of them.
    const Eigen::Vector3d root = limb_global[limb.root].translation();
    const double reach = (rest[limb.tip] - rest[limb.root]).norm() + kNearM;
    double farthest = 0;
    int count = 0;
    for (const Eigen::Vector3d& u : unexplained) {
      const double d = (u - root).norm();
      if (d > reach) continue;
      ++count;
      farthest = std::max(farthest, d);
    }
    if (count < kMinUnexplained) continue;
    Eigen::Vector3d target = Eigen::Vector3d::Zero();
    int far = 0;
    for (const Eigen::Vector3d& u : unexplained) {
      const double d = (u - root).norm();
      if (d > reach || d < 0.7 * farthest) continue;
      target += u;
      ++far;
    }
    target /= double(far);
    if ((limb_global[limb.end].translation() - target).norm() < kNearM) continue;
    // The limb straightened, then turned at its root so that it points at the target.
    Pose& q = limb_trial;
    q = p;
    q.angles_rad[size_t(limb.middle)].setZero();
    q.angles_rad[size_t(limb.end)].setZero();
    skeleton.forwardKinematics(q, global);
    const Eigen::Vector3d along = global[limb.end].translation() - global[limb.root].translation();
    const Eigen::Matrix3d turn =
        Eigen::Quaterniond::FromTwoVectors(along, target - root).toRotationMatrix();
    const int parent = skeleton.joint(limb.root).parent;
    q.angles_rad[size_t(limb.root)] =
        eulerAnglesOf(global[parent].linear().transpose() * turn * global[limb.root].linear());
    skeleton.clampToLimits(q);
    // Only the limb moves: fitted whole from a limb pointed elsewhere, the body could turn round
    // to face the other way, which the silhouettes cannot tell (six cameras: a turning actor's
    // MPJPE 46 -> 309 mm).
    holdAllBut(limb);
    const double c = fit(q, iterations);
    dof_held.clear();
    if (c < best_cost) best_cost = c, best = q;
  }
  use_prior = prior;
  if (best_cost >= (1 - kMinGain) * base) return false;
  // Kept only when it explains the silhouettes' edges that were not.
  skeleton.forwardKinematics(best, global);
  placeCapsules();
  if (unexplainedRays() > kKeptRays * rays) return false;
  spdlog::debug(
      "tracker: a limb recovered where the hull was unexplained: cost {:.4f} -> {:.4f}, {} rays "
      "unexplained",
      base, best_cost, rays);
  p = best;
  return true;
}

}  // namespace lumistage
