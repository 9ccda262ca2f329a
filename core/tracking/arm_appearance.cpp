// The arms placed by appearance (PoseTracker::Impl, pose_tracker_impl.h). Silhouettes cannot tell
// a forearm held up before the chest from one across the belly: both leave the outline the same,
// and the belly the arm should not fill draws the fit toward the second. The cameras' colours can:
// where the body is posed right, each point of its surface is the same stuff (skin, a shirt's
// stripe) in every camera that sees it; where an arm is posed wrong, the torso's surface behind
// the real arm, and the wrong arm's own, are seen as skin by one camera and shirt by another.
// Each arm is tried elsewhere and fitted, and kept where the cameras agree best among the
// placements that fit the silhouettes nearly as well.
#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/tracking/pose_tracker_impl.h"

namespace lumistage {

using namespace tracker_detail;

namespace {

// Points a capsule, for the colours' spread: along its axis, around it.
constexpr int kAlong = 4, kAround = 8;
// A point a camera sees: its surface turned toward the camera by more than this cosine.
constexpr double kMinFacing = 0.25;
// A placement is tried when its fit costs at most this much more than the pose's.
constexpr double kCostSlack = 0.10;
// And kept when it lowers the colours' spread by this share.
constexpr double kMinSpreadGain = 0.10;
// How far the shoulder's and the elbow's angles are turned for a trial, radians.
constexpr double kTurn = 0.8;

bool isLeg(int joint) {
  return (joint >= kRightHip && joint <= kRightFoot) || (joint >= kLeftHip && joint <= kLeftFoot);
}

}  // namespace

int PoseTracker::Impl::colouredCameras() const {
  int count = 0;
  for (const CellColours* c : colours) count += c != nullptr;
  return count;
}

bool PoseTracker::Impl::placeArmsWhenColoured(Pose& p, double& cost) {
  if (colouredCameras() < 2) return false;
  arms_pending = false;
  return placeArmsByAppearance(p, cost, kArmIterations, kArmStride);
}

double PoseTracker::Impl::colourSpread(const Pose& p) {
  if (colouredCameras() < 2) return -1;
  skeleton.forwardKinematics(p, global);
  capsuleEnds(spread_a, spread_b);
  const std::vector<Eigen::Vector3d>&a = spread_a, &b = spread_b;
  const size_t count = capsules.size();
  double spread = 0, degrees = 0;
  Eigen::Vector3d on_ray, on_segment;
  for (size_t k = 0; k < count; ++k) {
    if (isLeg(capsules[k].joint)) continue;  // the arms hide and show the torso, never the legs
    const Eigen::Vector3d axis = b[k] - a[k];
    const double length = axis.norm();
    if (length < 1e-6) continue;
    const Eigen::Vector3d u = axis / length;
    const Eigen::Vector3d e1 = u.unitOrthogonal(), e2 = u.cross(e1);
    const double r = capsules[k].radius_m;
    for (int i = 0; i < kAlong; ++i) {
      const Eigen::Vector3d centre = a[k] + (double(i) + 0.5) / kAlong * axis;
      for (int j = 0; j < kAround; ++j) {
        const double angle = 2 * std::numbers::pi * j / kAround;
        const Eigen::Vector3d normal = std::cos(angle) * e1 + std::sin(angle) * e2;
        const Eigen::Vector3d x = centre + r * normal;
        Eigen::Vector2d sum = Eigen::Vector2d::Zero();
        double squares = 0;
        int seen = 0;
        for (int c = 0; c < cameras; ++c) {
          const CellColours* colour = colours[size_t(c)];
          if (!colour) continue;
          const Camera& camera = rig.camera(c);
          const Eigen::Vector3d to_camera = camera.centre() - x;
          const double distance = to_camera.norm();
          if (normal.dot(to_camera) < kMinFacing * distance) continue;
          const Eigen::Vector3d d = to_camera / distance;
          bool hidden = false;
          for (size_t o = 0; o < count && !hidden; ++o) {
            if (o == k) continue;
            hidden =
                raySegmentDistance(x, d, a[o], b[o], on_ray, on_segment) < capsules[o].radius_m &&
                (on_ray - x).norm() > 1e-3;
          }
          if (hidden) continue;
          const std::optional<Eigen::Vector2d> pixel = camera.project(x);
          if (!pixel) continue;
          const int cx = int(std::floor(pixel->x() / colour->step)),
                    cy = int(std::floor(pixel->y() / colour->step));
          if (cx < 0 || cy < 0 || cx >= colour->width || cy >= colour->height) continue;
          const uint8_t* q = colour->at(cx, cy);
          const double total = double(q[0]) + q[1] + q[2];
          if (total <= 0) continue;  // not the actor in this camera
          const Eigen::Vector2d chroma(q[0] / total, q[1] / total);
          sum += chroma;
          squares += chroma.squaredNorm();
          ++seen;
        }
        if (seen < 2) continue;
        spread += squares - sum.squaredNorm() / seen;
        degrees += seen - 1;
      }
    }
  }
  return degrees > 0 ? spread / degrees : -1;
}

bool PoseTracker::Impl::placeArmsByAppearance(Pose& p, double& cost, int iterations, int stride) {
  const double base_spread = colourSpread(p);
  if (base_spread <= 0) return false;
  const bool prior = use_prior;
  use_prior = false;
  const double full_cost = evaluate(p, false, H, g);
  arm_start = p;
  // The trials on a thinned hull and rim; the cost compared on the same.
  thinSamples(stride);
  cost = evaluate(p, false, H, g);
  double spread = base_spread;
  bool moved = false;
  for (const Limb& arm : {kLimbs[0], kLimbs[1]}) {
    // The elbow's bending axis: the one its limits open most.
    const JointLimits& elbow_limits = skeleton.joint(arm.middle).limits;
    int bend = 0;
    (elbow_limits.upper_rad - elbow_limits.lower_rad).maxCoeff(&bend);
    holdAllBut(arm);
    arm_best = p;
    double best_spread = spread, best_cost = cost;
    for (int axis = 0; axis < 3; ++axis) {
      for (double turn : {kTurn, -kTurn}) {
        for (double elbow : {0.0, kTurn, -kTurn}) {
          arm_trial = p;
          arm_trial.angles_rad[size_t(arm.root)][axis] += turn;
          arm_trial.angles_rad[size_t(arm.middle)][bend] += elbow;
          skeleton.clampToLimits(arm_trial);
          const double c = fit(arm_trial, iterations);
          if (c > (1 + kCostSlack) * cost) continue;
          const double s = colourSpread(arm_trial);
          if (s >= 0 && s < best_spread) best_spread = s, best_cost = c, arm_best = arm_trial;
        }
      }
    }
    dof_held.clear();
    if (best_spread < (1 - kMinSpreadGain) * spread) {
      spdlog::debug(
          "tracker: an arm placed by its colours: spread {:.5f} -> {:.5f}, cost {:.4f} -> {:.4f}",
          spread, best_spread, cost, best_cost);
      p = arm_best;
      cost = best_cost;
      spread = best_spread;
      moved = true;
    }
  }
  fullSamples();
  cost = evaluate(p, false, H, g);
  // Judged on every sample, a placement that fits much worse than the thinned ones said is not
  // kept (on every 16th sample, one boxer's arm was moved where his fit then failed).
  if (moved && cost > (1 + kCostSlack) * full_cost) {
    p = arm_start;
    cost = full_cost;
    moved = false;
  }
  use_prior = prior;
  return moved;
}

}  // namespace lumistage
