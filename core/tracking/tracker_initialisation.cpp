// The tracker's initialisation and shape calibration (PoseTracker::Impl, pose_tracker_impl.h):
// finding the actor in any pose, at any heading, anywhere on the stage, and the body's proportions.
#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "core/tracking/pose_library.h"
#include "core/tracking/pose_tracker_impl.h"

namespace lumistage {

using namespace tracker_detail;

namespace {

// Initialisation calibrates the body's proportions only on a hull that the best hypothesis fits
// within this many times lost_rms_m.
constexpr double kCalibrateWithin = 2.0;
// Headings each library pose is tried at (45 degrees apart: the fit turns the rest of the way), the
// hull samples the hypotheses are scored on (every kScoreStride-th), and the best hypotheses then
// fitted in full.
constexpr int kHeadings = 8;
constexpr int kScoreStride = 8;
// The best hypotheses fitted, and the shape calibration's trials, on every kFitStride-th sample
// of the hull and the rim; the winner then on all of them. 4 against 1 on the development corpus
// (seeds 1-20, 30 frames): MPJPE 19.6 -> 19.3 mm (built-in clips), 31.4 -> 27.5 mm (with the BVH
// captures), initialisation 490 -> 305 ms on an 11-camera stage (2 gave two stages turned round).
constexpr int kFitStride = 4;
constexpr int kFittedHypotheses = 6;
// A hull whose top is lower than this is nobody standing, crouching or sitting (a bag, a box): a
// short actor sitting on the floor, hunched, stands 0.68 m high.
constexpr double kLowestTopM = 0.6;

}  // namespace

void PoseTracker::Impl::thinSamples(int stride) {
  if (!thinned) {
    full_hull.swap(hull);
    full_rim.swap(rim);
    thinned = true;
  }
  hull.clear();
  rim.clear();
  for (size_t i = 0; i < full_hull.size(); i += size_t(stride)) hull.push_back(full_hull[i]);
  for (size_t i = 0; i < full_rim.size(); i += size_t(stride)) rim.push_back(full_rim[i]);
  candidates_valid = false;
}

void PoseTracker::Impl::fullSamples() {
  if (!thinned) return;
  hull.swap(full_hull);
  rim.swap(full_rim);
  thinned = false;
  candidates_valid = false;
}

void PoseTracker::Impl::modelExtent(const Pose& p, double& bottom, double& top, double* crown) {
  skeleton.forwardKinematics(p, global);
  bottom = std::numeric_limits<double>::infinity();
  top = -bottom;
  if (crown) *crown = top;
  for (const Capsule& c : capsules) {
    const Eigen::Isometry3d& t = global[c.joint];
    for (const Eigen::Vector3d& end : {c.a, c.b}) {
      const double z = (t * end).z();
      bottom = std::min(bottom, z - c.radius_m);
      top = std::max(top, z + c.radius_m);
      if (crown && c.joint == kHead) *crown = std::max(*crown, z + c.radius_m);
    }
  }
}

double PoseTracker::Impl::uprightness(const Pose& p, bool to_crown) {
  double bottom, top, crown;
  modelExtent(p, bottom, top, &crown);
  return ((to_crown ? crown : top) - bottom) / rest_extent_m;
}

void PoseTracker::Impl::remeasureHeight(double hull_bottom, double hull_top) {
  // Straighter by this much than the frame the height came from: measured again. Below it, the
  // pose's own error (a knee bent a little more or less) would move the height more than the
  // posture does.
  constexpr double kStraighter = 0.02;
  // Standing straight: the height holds. (The fitted pose's own uprightness, a knee bent a little
  // more or less, is no measure of a standing actor's: it made the height and the legs trade.)
  constexpr double kStanding = 0.97;
  // A limb higher than the head's top by this much (a hand's, not a capsule's rounding): the
  // hull's top is no crown to measure to.
  constexpr double kAboveHeadM = 0.05;
  if (height_uprightness >= kStanding) return;
  double bottom, top, crown;
  modelExtent(pose, bottom, top, &crown);
  if (top > crown + kAboveHeadM) return;
  const double u = std::min(1.0, (top - bottom) / rest_extent_m);  // uprightness(pose)
  if (u < height_uprightness + kStraighter) return;
  const double height =
      heightSpanning(hull_top - hull_bottom - opt.hair_m, u, shape.leg_length_scale);
  height_uprightness = u;
  if (std::abs(height - shape.height_m) < 0.002) return;
  spdlog::debug("tracker: the actor stands straighter ({:.2f}): height {:.3f} -> {:.3f} m", u,
                shape.height_m, height);
  BodyShape s = shape;
  s.height_m = height;
  setShape(s);
  double new_bottom, new_top;
  modelExtent(pose, new_bottom, new_top);
  pose.root_translation_m.z() += bottom - new_bottom;
  previous.root_translation_m.z() += bottom - new_bottom;
}

void PoseTracker::Impl::makeLibrary() {
  library = makeInitialisationPoses(generic);
  library_bottom.resize(library.size());
  library_upright.resize(library.size());
  library_crown_upright.resize(library.size());
  for (size_t i = 0; i < library.size(); ++i) {
    double bottom, top;
    modelExtent(library[i], bottom, top);
    library_bottom[i] = bottom;
    library_upright[i] = uprightness(library[i]);
    library_crown_upright[i] = uprightness(library[i], true);
  }
  hypotheses.reserve(2 * library.size() * kHeadings);  // at the hull's top and at a crown
}

double PoseTracker::Impl::heightSpanning(double extent, double upright, double legs) const {
  // makeHumanSkeleton: the legs are 0.84 of the generic height unit (1.75 m).
  const double crown = generic_top_z - generic_bottom_z + 0.84 * (legs - 1.0);
  return std::clamp(BodyShape{}.height_m * extent / (crown * upright), 1.3, 2.3);
}

BodyShape PoseTracker::Impl::shapeSpanning(double extent_m, double upright) const {
  BodyShape s;
  s.height_m = heightSpanning(extent_m, upright, 1.0);
  return s;
}

Pose PoseTracker::Impl::placedLibraryPose(int i, double heading_rad,
                                          const Eigen::Vector3d& centroid, double bottom_z) {
  // The library's heights and offsets are the generic skeleton's: scaled to this one's.
  const double k = skeleton.restPositions()[0].z() / generic.restPositions()[0].z();
  Pose p = library[i];
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(heading_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  p.angles_rad[0] = rotationVectorOf(turn * rotationFromVector(p.angles_rad[0]));
  p.root_translation_m *= k;
  // Centred: the joints' mean over the hull's centroid.
  p.root_translation_m.x() = p.root_translation_m.y() = 0;
  skeleton.forwardKinematics(p, global);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Isometry3d& t : global) mean += t.translation();
  mean /= double(global.size());
  p.root_translation_m.x() = centroid.x() - mean.x();
  p.root_translation_m.y() = centroid.y() - mean.y();
  p.root_translation_m.z() += bottom_z - k * library_bottom[i];
  return p;
}

bool PoseTracker::Impl::initialise(TrackResult& out, double& volume) {
  Eigen::Vector3d centroid;
  double top_z = 0, bottom_z = 0;
  volume = carve(Eigen::Vector3i::Zero(), dims, &centroid, &top_z, &bottom_z);
  // The actor's piece of the hull, not the phantoms of a key's blotches or a bag across the stage
  // (an actor on a box the key takes for the screen would otherwise stand on their floor), and
  // the rim's rays that meet it. A hull of more than twice max_volume_m3 is a broken key, not an
  // actor beside a few phantoms, and is not searched for pieces (a grey stage keyed as green
  // fills the stage's box: 2.7 million voxels, 100 ms a frame).
  if (volume <= 2 * opt.max_volume_m3)
    if (const double kept = dropStrayPieces(centroid, top_z, bottom_z); kept > 0) volume = kept;
  dropRimRaysOffHull();
  out.hull_points = int(hull.size());
  if (volume < opt.min_volume_m3 || volume > opt.max_volume_m3 || top_z < kLowestTopM) return false;
  const bool calibrating = opt.calibrate_shape && !shape_calibrated;
  use_prior = false;
  // The body's vertical extent: the hull's less the hair above the crown. Both hands raised over
  // the head make the hull's top theirs, and a body scaled to it too tall, its head at the hands
  // (no library pose raises both): every pose is then also scaled from its head's top to the
  // crown found below them (its arms then found by recoverLimbs), and the search chooses.
  const double crown_z = calibrating ? crownBelowRaisedHands() : 0;
  const double extent = top_z - bottom_z - opt.hair_m;
  const double crown_extent = crown_z > 0 ? crown_z - bottom_z - opt.hair_m : 0;
  double straighter = 0;
  if (findActor(out, centroid, bottom_z, extent, crown_extent, 0, straighter)) return true;
  // Found as bent as a crouching library pose (a heavy boxer, whose girth a crouch's bent legs
  // fit best at the generic build), where the hull's own length from soles to crown says he
  // stands nearly straight, and no body of that height held: searched again, every pose as tall
  // as that length makes him.
  return calibrating && straighter > 0 &&
         findActor(out, centroid, bottom_z, extent, crown_extent, straighter, straighter);
}

bool PoseTracker::Impl::findActor(TrackResult& out, const Eigen::Vector3d& centroid,
                                  double bottom_z, double top_extent, double crown_extent,
                                  double fixed_upright, double& straighter) {
  // A hull whose length from soles to crown makes the body this much straighter than the pose
  // it was found in did: `straighter` set for a search again.
  constexpr double kStraighterBy = 0.1;
  const bool calibrating = opt.calibrate_shape && !shape_calibrated;
  const BodyShape known = shape;
  straighter = 0;
  // Every library pose at every heading, over the hull's centroid, standing on its lowest point,
  // scaled (until calibrated) to the hull's height in that pose, and to the crown's (or as
  // upright as `fixed_upright`, where given); scored on a thinned hull and rim.
  // Only the best kFittedHypotheses are fitted: a hypothesis is given up as soon as its cost
  // passes theirs so far (`kept`, a max-heap of the best costs, infinite until that many are in).
  thinSamples(kScoreStride);
  hypotheses.clear();
  std::array<double, kFittedHypotheses> kept;
  kept.fill(std::numeric_limits<double>::infinity());
  for (int i = 0; i < int(library.size()); ++i) {
    for (const bool crown : {false, true}) {
      if (crown && crown_extent <= 0) continue;
      const double upright = fixed_upright > 0 ? fixed_upright
                             : crown           ? library_crown_upright[i]
                                               : library_upright[i];
      if (calibrating) setShape(shapeSpanning(crown ? crown_extent : top_extent, upright));
      for (int h = 0; h < kHeadings; ++h) {
        const double heading = 2 * std::numbers::pi * h / kHeadings;
        const Pose p = placedLibraryPose(i, heading, centroid, bottom_z);
        const double cost = score(p, kept.front());
        hypotheses.push_back({cost, i, heading, shape.height_m, upright, crown});
        if (cost < kept.front()) {
          std::pop_heap(kept.begin(), kept.end());
          kept.back() = cost;
          std::push_heap(kept.begin(), kept.end());
        }
      }
    }
  }
  // The best fitted on a thinned hull and rim, the winner then on all of them.
  thinSamples(kFitStride);
  const int fitted_count = std::min<int>(kFittedHypotheses, int(hypotheses.size()));
  std::partial_sort(hypotheses.begin(), hypotheses.begin() + fitted_count, hypotheses.end(),
                    [](const Hypothesis& a, const Hypothesis& b) { return a.cost < b.cost; });
  Pose best_pose;
  BodyShape best_shape = known;
  double best = std::numeric_limits<double>::infinity(), best_upright = 1;
  bool to_crown = false;
  for (int k = 0; k < fitted_count; ++k) {
    const Hypothesis& h = hypotheses[k];
    if (calibrating) {
      BodyShape s;
      s.height_m = h.height_m;
      setShape(s);
    }
    Pose p = placedLibraryPose(h.pose, h.heading_rad, centroid, bottom_z);
    const double c = fit(p, opt.init_iterations);
    if (c < best)
      best = c, best_pose = p, best_shape = shape, best_upright = h.upright, to_crown = h.crown;
  }
  fullSamples();
  setShape(best_shape);
  best = fit(best_pose, opt.init_iterations / 2);
  // A limb the library's poses never hold (both hands over the head) is looked for where the
  // hull is unexplained; the body's uprightness is then the pose's own, not its library pose's.
  const int rays = countUnexplained(best_pose);
  if (rays > 0 && recoverLimbs(best_pose, rays, opt.init_iterations)) {
    best = evaluate(best_pose, false, H, g);
    best_upright = uprightness(best_pose, to_crown);
  }
  const double extent = to_crown ? crown_extent : top_extent;
  // A hull that no hypothesis fits within twice the lost threshold (two people, a prop, a hull
  // carved by two cameras) is no body whose proportions a search could find: failed at once.
  double rms = fitRms(best_pose);
  if (calibrating && rms > kCalibrateWithin * opt.lost_rms_m) {
    out.fit_rms_m = rms;
    return false;
  }
  if (calibrating) {
    // A body that stands less straight than its pose says (a boxer's bent knees, found in a
    // standing pose) is as tall as the hull's length from soles to crown, which follows the bend.
    // Where the pose is the more bent, the pose holds: a deep crouch's hull fills the space
    // between the thighs and the body, and the path cuts across it.
    const double length = crownToSole(best_pose) - opt.hair_m;
    if (length > 0.5 * extent) {
      if (extent / length > best_upright + kStraighterBy)
        straighter = std::min(1.0, extent / length);
      best_upright = std::min(best_upright, extent / length);
    }
    calibrateShape(best_pose, extent, best_upright, best, false);
    rms = fitRms(best_pose);
    if (rms > opt.lost_rms_m) {
      calibrateShape(best_pose, extent, best_upright, best, true);
      rms = fitRms(best_pose);
    }
  }
  // An arm the silhouettes place in two ways (before the chest or across the belly) placed where
  // the cameras' colours agree; without colours this frame, in the first tracked frame with them.
  arms_pending = opt.arm_appearance;
  if (arms_pending && placeArmsWhenColoured(best_pose, best)) rms = fitRms(best_pose);
  out.fit_rms_m = rms;
  out.rim_rms_m = rimRms(best_pose);
  if (!fitHolds(rms, out.rim_rms_m)) {
    // A hull no body fits (a prop, someone half inside the stage, a hull carved by some cameras
    // only) is no actor to take the proportions from: the next initialisation calibrates anew.
    if (calibrating) {
      foot_scale = 1.0;
      setShape(known);
    }
    return false;
  }
  if (calibrating) {
    shape_calibrated = true;
    height_uprightness = best_upright;
  }
  pose = previous = best_pose;
  has_previous = false;
  makeTwin(best, opt.init_iterations);
  return true;
}

void PoseTracker::Impl::calibrateShape(Pose& best_pose, double extent, double upright, double& best,
                                       bool heavy) {
  // Coordinate search over the body's proportions, refitting the pose for every trial. Which of
  // them: the legs' length, the girth and the feet (shoes). The hull's extent fixes the body's
  // overall size in its pose, so a trial leg length trades the legs against the rest of the body:
  // searching the legs with a free height, or the arms, lowered the fit's cost but raised the
  // joints' error (the capsules are too coarse to tell bone lengths apart on their own).
  // A heavy actor's search (`heavy`: the first left the fit above lost_rms_m) starts from the
  // first one's result with larger steps of the girth and the belly: the first one's halving steps
  // reach a girth of 1.23 at most, which holds a clothed actor of the generic build (searched
  // further, the girth grew past the actor's and the joints' error with it: the reference walk
  // 13.9 -> 17.5 mm) but leaves a heavy one unfitted, and never found at all.
  constexpr int kParams = 8;
  const int calibrated_params = heavy ? 0xa0 : 0x64;
  double k[kParams] = {shape.height_m,
                       shape.arm_length_scale,
                       shape.leg_length_scale,
                       shape.shoulder_width_scale,
                       shape.hip_width_scale,
                       shape.girth_scale,
                       foot_scale,
                       shape.belly_scale};
  double steps[kParams] = {0.06, 0.06, 0.06, 0.08, 0.08, heavy ? 0.2 : 0.12, 0.2, 0.2};
  const double lo[kParams] = {1.3, 0.8, 0.8, 0.7, 0.7, 0.7, 0.8, 0.8},
               hi[kParams] = {2.3, 1.25, 1.25, 1.4, 1.4, 1.8, 2.0, 1.8};
  // The shape with these proportions whose body spans `extent` as upright as the pose found.
  const auto make = [&](const double* v) {
    foot_scale = v[6];
    BodyShape s;
    s.arm_length_scale = v[1];
    s.leg_length_scale = v[2];
    s.shoulder_width_scale = v[3];
    s.hip_width_scale = v[4];
    s.girth_scale = v[5];
    s.belly_scale = v[7];
    s.height_m = heightSpanning(extent, upright, v[2]);
    return s;
  };
  // The trials on a thinned hull and rim; the result fitted on all of them.
  thinSamples(kFitStride);
  best = evaluate(best_pose, false, H, g);
  for (int round = 0; round < 5; ++round) {
    for (int i = 0; i < kParams; ++i) {
      if (!((calibrated_params >> i) & 1)) continue;
      for (double sign : {1.0, -1.0}) {
        double trial[kParams];
        std::copy(k, k + kParams, trial);
        trial[i] = std::clamp(trial[i] + sign * steps[i], lo[i], hi[i]);
        if (trial[i] == k[i]) continue;
        setShape(make(trial));
        Pose p = best_pose;
        const double c = fit(p, 12);
        if (c < best) {
          best = c;
          best_pose = p;
          std::copy(trial, trial + kParams, k);
          break;
        }
      }
    }
    for (double& s : steps) s *= 0.5;
  }
  fullSamples();
  setShape(make(k));
  best = fit(best_pose, opt.init_iterations);
}

}  // namespace lumistage
