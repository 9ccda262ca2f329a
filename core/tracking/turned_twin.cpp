// The tracker's turned twin (PoseTracker::Impl, pose_tracker_impl.h): silhouettes barely tell an
// actor's front from his back (a guard held before the chest, arms at the sides, legs straight),
// and an initialisation that picks the wrong one keeps it: every joint of the left side on the
// right. So the pose found is tracked with its twin, turned half round about the vertical, for the
// first frames after each initialisation; as the actor moves (a knee bends, an elbow bends: each
// only one way) the wrong one fits worse, and the better of the two is kept. An actor who holds
// still gives the fit nothing to tell them by: the feet, whose toes reach ahead of the ankles,
// decide. A body that leans (hanging from a bar) whose turned twin is no rival is also reflected
// through its frontal plane, and the twin that fits better is tracked.
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "core/body/human_skeleton.h"
#include "core/tracking/pose_library.h"
#include "core/tracking/pose_tracker_impl.h"

namespace lumistage {

using namespace tracker_detail;

namespace {

// The twin is tracked for this many frames; it takes over when its fit's cost summed over them is
// below this share of the pose's. On the reference rig's walk started from a still stance, a twin
// that was wrong ended at 0.90-0.92 of the pose's cost at two headings of eight (the first frames
// of a motion fit worse either way); on the held-out boxer it replaced, the right one at 0.84.
constexpr int kTwinFrames = 8;
constexpr double kTwinWins = 0.9;
// A twin that fits this much worse than the pose at once is no rival: silhouettes told them apart.
constexpr double kTwinRival = 1.5;
// A twin whose cost summed over kTwinEarlyFrames frames or more is below this share of the pose's
// takes over at once: the silhouettes told them apart (an actor found facing the wrong way in a
// pose that is not symmetric).
constexpr int kTwinEarlyFrames = 2;
constexpr double kTwinClearlyWins = 0.6;
// A body whose length (ankles to head) leans more than this off the vertical is also reflected
// through its frontal plane.
constexpr double kLeaningRad = 0.17;
// Between kTwinWins and as good as the pose, the cost cannot tell them (a still, symmetric pose:
// an A-pose held, on few cameras): the feet do. The twin then takes over when its toes reach this
// much further into the hull's feet than the pose's (each foot's low hull lies mostly ahead of its
// ankle, toward the toes).
constexpr double kFeetMarginM = 0.02;
// The hull's feet: its samples this high above a foot's ankle at most, within this reach of it.
constexpr double kFootAboveAnkleM = 0.04, kFootReachM = 0.22;

}  // namespace

void PoseTracker::Impl::predictFrom(const Pose& now, const Pose& before, Pose& predicted) const {
  predicted = now;
  const double k = opt.velocity_gain;
  predicted.root_translation_m += k * (now.root_translation_m - before.root_translation_m);
  const Eigen::Matrix3d r_now = rotationFromVector(now.angles_rad[0]),
                        r_before = rotationFromVector(before.angles_rad[0]);
  const Eigen::AngleAxisd turn(r_now * r_before.transpose());
  const Eigen::AngleAxisd root(Eigen::AngleAxisd(k * turn.angle(), turn.axis()) * r_now);
  predicted.angles_rad[0] = root.angle() * root.axis();
  for (size_t j = 1; j < predicted.angles_rad.size(); ++j)
    predicted.angles_rad[j] += k * (now.angles_rad[j] - before.angles_rad[j]);
  skeleton.clampToLimits(predicted);
}

void PoseTracker::Impl::makeTwin(double pose_cost, int iterations) {
  twin_frames = 0;
  // Turned half round about the vertical through the joints' mean.
  skeleton.forwardKinematics(pose, global);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Isometry3d& t : global) mean += t.translation();
  mean /= double(global.size());
  const Eigen::Matrix3d half =
      Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  twin = pose;
  twin.angles_rad[0] = rotationVectorOf(half * rotationFromVector(pose.angles_rad[0]));
  const Eigen::Vector3d root = global[0].translation();
  const Eigen::Vector3d turned = mean + half * (root - mean);
  twin.root_translation_m += turned - root;
  // A body that leans (hanging from a bar, leaning on a wall) is seen alike from the front and
  // the back through its frontal plane, which holds its length (ankles to head) and not the
  // vertical: where the turned twin is no rival, it is reflected through that plane instead (its
  // left side where its right was, mirroredPose), and the twin that fits better kept.
  const Eigen::Vector3d ankles =
      0.5 * (global[kRightAnkle].translation() + global[kLeftAnkle].translation());
  const Eigen::Vector3d length = (global[kHead].translation() - ankles).normalized();
  Eigen::Vector3d front = global[0].linear() * Eigen::Vector3d::UnitY();
  front = (front - front.dot(length) * length).normalized();
  double cost = fit(twin, iterations);
  if (!(cost < kTwinRival * pose_cost) && length.z() < std::cos(kLeaningRad)) {
    const Eigen::Matrix3d reflect = Eigen::Matrix3d::Identity() - 2 * front * front.transpose();
    Pose mirror = mirroredPose(pose);
    mirror.angles_rad[0] = rotationVectorOf(reflect * Eigen::Vector3d(-1, 1, 1).asDiagonal() *
                                            rotationFromVector(mirror.angles_rad[0]));
    mirror.root_translation_m = pose.root_translation_m + reflect * (root - mean) + mean - root;
    const double c = fit(mirror, iterations);
    if (c < cost) twin = mirror, cost = c;
  }
  if (!(cost < kTwinRival * pose_cost)) return;
  // Clearly better at once, or as close in cost as the fit cannot tell apart and its toes point
  // into the hull's feet: the twin is tracked from now on, the pose as its twin (which motion may
  // still bring back).
  if (cost < kTwinWins * pose_cost || (cost < pose_cost / kTwinWins && feetFavourTwin())) {
    std::swap(pose, twin);
    std::swap(cost, pose_cost);
    previous = pose;
  }
  twin_previous = twin;
  twin_cost = cost;
  pose_cost_sum = pose_cost;
  twin_frames = kTwinFrames;
}

double PoseTracker::Impl::feetAhead(const Pose& p) {
  skeleton.forwardKinematics(p, global);
  double sum = 0;
  int feet = 0;
  for (const auto& [ankle_joint, foot_joint] :
       {std::pair{kRightAnkle, kRightFoot}, std::pair{kLeftAnkle, kLeftFoot}}) {
    const Eigen::Vector3d ankle = global[ankle_joint].translation();
    const Eigen::Vector3d other =
        global[ankle_joint == kRightAnkle ? kLeftAnkle : kRightAnkle].translation();
    Eigen::Vector2d toes = (global[foot_joint].translation() - ankle).head<2>();
    if (toes.norm() < 1e-3) continue;
    toes.normalize();
    Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
    int count = 0;
    for (const Eigen::Vector3d& h : hull) {
      if (h.z() > ankle.z() + kFootAboveAnkleM) continue;
      const Eigen::Vector2d d = (h - ankle).head<2>();
      if (d.norm() > kFootReachM || d.squaredNorm() > (h - other).head<2>().squaredNorm()) continue;
      centroid += d;
      ++count;
    }
    if (count == 0) continue;
    sum += (centroid / count).dot(toes);
    ++feet;
  }
  return feet > 0 ? sum / feet : 0.0;
}

bool PoseTracker::Impl::feetFavourTwin() {
  return feetAhead(twin) > feetAhead(pose) + kFeetMarginM;
}

bool PoseTracker::Impl::trackTwin(double pose_cost) {
  if (twin_frames <= 0) return false;
  predictFrom(twin, twin_previous, prior_pose);
  use_prior = true;
  prior_weight = opt.prior_weight;
  twin_previous = twin;
  twin = prior_pose;
  fit(twin, opt.iterations);
  use_prior = false;
  twin_cost += evaluate(twin, false, H, g);
  pose_cost_sum += pose_cost;
  if (twin_cost > kTwinRival * pose_cost_sum) {  // fallen behind for good
    twin_frames = 0;
    return false;
  }
  --twin_frames;
  if (kTwinFrames - twin_frames >= kTwinEarlyFrames && twin_cost < kTwinClearlyWins * pose_cost_sum)
    twin_frames = 0;  // clearly better already
  if (twin_frames > 0) return false;
  if (!(twin_cost < kTwinWins * pose_cost_sum) && !(twin_cost < pose_cost_sum && feetFavourTwin()))
    return false;
  previous = twin_previous;
  pose = twin;
  return true;
}

}  // namespace lumistage
