#pragma once

// The tracker's insides (PoseTracker::Impl), shared by the files that make it up: the body model
// and the frame's course (pose_tracker.cpp), the visual hull (hull_carving.cpp), the fit
// (tracker_fit.cpp), and the initialisation and shape calibration (tracker_initialisation.cpp).
// Not for use outside core/tracking.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/geometry/rotation.h"
#include "core/tracking/pose_tracker.h"

namespace lumistage {

namespace tracker_detail {

// A voxel's cell in a camera's silhouette, or kUnseen<T> where the camera does not see it: 16 bits
// a cell while every camera has fewer than 65535 cells (1024x768 at step 4), 32 beyond (1920x1080).
template <typename T>
constexpr T kUnseen = std::numeric_limits<T>::max();

// A capsule hung on joint `joint`, along its segment: to its child `child`, or along `end_dir`
// (1 m in the generic skeleton) for an end joint. The axis runs from fraction a_frac to b_frac of
// the segment, shifted sideways by `lateral_m` (the torso is two capsules side by side); all
// measured on the generic mesh, then scaled with the calibrated skeleton.
struct Capsule {
  int joint = 0;
  int child = -1;
  Eigen::Vector3d end_dir = Eigen::Vector3d::UnitZ();
  double a_frac = 0, b_frac = 1;
  Eigen::Vector3d lateral_m = Eigen::Vector3d::Zero();
  double generic_radius_m = 0;
  // For the current skeleton: the axis relative to the joint (rest-aligned frame).
  Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
  double radius_m = 0;
};

// An arm or a leg, root to tip: shoulder, elbow, wrist, hand (hip, knee, ankle, foot). The arms
// first.
struct Limb {
  int root, middle, end, tip;
};
inline constexpr Limb kLimbs[] = {{kRightShoulder, kRightElbow, kRightWrist, kRightHand},
                                  {kLeftShoulder, kLeftElbow, kLeftWrist, kLeftHand},
                                  {kRightHip, kRightKnee, kRightAnkle, kRightFoot},
                                  {kLeftHip, kLeftKnee, kLeftAnkle, kLeftFoot}};

struct Sample {  // an axis sample that must project inside every silhouette
  int joint;
  Eigen::Vector3d local;
};

// One degree of freedom of the fit: root translation axis, root rotation axis (applied on the
// left, about the root), or one Euler angle of a joint.
struct Dof {
  enum Kind { kTranslation, kRootRotation, kEuler } kind;
  int joint;
  int axis;
};

// A viewing ray through a silhouette's edge (its origin the camera's centre, its direction of unit
// length): the body touches it.
struct RimRay {
  Eigen::Vector3d origin, direction;
  int camera;
  int cell;  // the edge's cell in the camera's silhouette (y * width + x)
};

// The distance between a ray (origin o, unit direction d, s >= 0) and segment a-b, with the
// closest points on each.
inline double raySegmentDistance(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                 const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                 Eigen::Vector3d& on_ray, Eigen::Vector3d& on_segment) {
  const Eigen::Vector3d u = b - a, w0 = o - a;
  const double B = d.dot(u), C = u.squaredNorm(), D = d.dot(w0), E = u.dot(w0);
  const double denom = C - B * B;
  double t = denom > 1e-12 * C ? std::clamp((E - B * D) / denom, 0.0, 1.0) : 0.0;
  double s = t * B - D;
  if (s < 0) {
    s = 0;
    t = C > 0 ? std::clamp(E / C, 0.0, 1.0) : 0.0;
  }
  on_ray = o + s * d;
  on_segment = a + t * u;
  return (on_ray - on_segment).norm();
}

// The distance between segments a0-a1 and b0-b1, with the closest points on each (Ericson,
// Real-Time Collision Detection, 5.1.9).
inline double segmentSegmentDistance(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1,
                                     const Eigen::Vector3d& b0, const Eigen::Vector3d& b1,
                                     Eigen::Vector3d& on_a, Eigen::Vector3d& on_b) {
  const Eigen::Vector3d d1 = a1 - a0, d2 = b1 - b0, r = a0 - b0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (a <= 1e-12 && e <= 1e-12) {
    s = t = 0;
  } else if (a <= 1e-12) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 1e-12) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 1e-12 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  on_a = a0 + s * d1;
  on_b = b0 + t * d2;
  return (on_a - on_b).norm();
}

// Huber's robust cost of a residual `r`: quadratic within `delta`, linear beyond.
inline double huber(double r, double delta) {
  const double ar = std::abs(r);
  return ar <= delta ? 0.5 * r * r : delta * (ar - 0.5 * delta);
}

inline double segmentDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                              const Eigen::Vector3d& b, Eigen::Vector3d& closest) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  double t = len2 > 0 ? (p - a).dot(ab) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  closest = a + t * ab;
  return (p - closest).norm();
}

}  // namespace tracker_detail

struct PoseTracker::Impl {
  using Capsule = tracker_detail::Capsule;
  using Sample = tracker_detail::Sample;
  using Dof = tracker_detail::Dof;
  using RimRay = tracker_detail::RimRay;
  template <typename T>
  static constexpr T kUnseen = tracker_detail::kUnseen<T>;
  PoseTrackerOptions opt;
  Rig rig;
  int cameras = 0;
  std::vector<int> cell_w, cell_h;
  // Hull grid.
  StageBox stage;
  Eigen::Vector3d lower;
  Eigen::Vector3i dims;
  // [voxel * cameras + camera]: cell while every camera's cells fit in 16 bits, else cell_wide.
  std::vector<uint16_t> cell;
  std::vector<uint32_t> cell_wide;
  // Blocks of kBlock^3 voxels, [block * cameras + camera]: a cell of one of the block's voxels and
  // how far (in cells, rounded up) every other voxel's cell lies from it, or kUnseen where the
  // camera does not see all of the block. A camera whose distance transform at that cell exceeds
  // the reach carves the whole block away (the transform moves by at most a cell a cell), so the
  // empty space around the actor is carved a block at a time instead of a voxel at a time.
  static constexpr int kBlock = 4;
  Eigen::Vector3i block_dims;
  std::vector<uint32_t> block_cell;
  std::vector<uint8_t> block_reach;
  // The last carve's voxels (1 kept), set within the box occupied_lo..occupied_hi (empty when hi <
  // lo) until the next carve clears it.
  std::vector<uint8_t> occupied;
  Eigen::Vector3i occupied_lo = Eigen::Vector3i::Zero(), occupied_hi = -Eigen::Vector3i::Ones();
  void clearOccupied();
  // The hull's length from the soles to the crown of the body posed in `p`, metres, along the
  // shortest path inside the last carve's voxels (hull_geodesic.cpp): the body's height whatever
  // its posture, a crouch's bent knees and hips followed instead of cut short. 0 where the hull
  // holds no crown near the head's or no sole.
  double crownToSole(const Pose& p);
  // The height (m) of a head's crown below two hands raised over it: the highest top of the last
  // carve's voxels under which the hull is as wide as a head, 0.08-0.5 m below the hull's top and
  // below two tops as narrow as forearms (hull_crown.cpp). 0 where the hull's top is a head's,
  // one hand at most is raised over it (the library's waves), or no head is found.
  double crownBelowRaisedHands();
  std::vector<int> crown_label;  // its scratch: a layer's sections
  std::vector<std::pair<int, int>> crown_stack;
  // Leaves out of the last carve the pieces of the hull (26-connected) that lie apart from the
  // largest, the actor's (further than hull_pieces.cpp's kNearActorM): the carving's phantoms of
  // a key's blotches on the floor, a prop across the stage. Where it drops any, the hull's surface
  // is sampled again and its centroid, top and bottom (m) set; returns the volume kept, or 0 where
  // it drops nothing.
  double dropStrayPieces(Eigen::Vector3d& centroid, double& top_z, double& bottom_z);
  // Leaves out of the rim the rays through the edges of a silhouette's parts (8-connected cells)
  // none of whose rays passes a voxel of the last carve (or its face neighbours): a key's blotches
  // on the floor, which no other camera agrees with and no body could explain
  // (silhouette_rim.cpp).
  void dropRimRaysOffHull();
  std::vector<uint8_t> rim_on_hull, rim_part;  // its scratch
  std::vector<int> rim_flood, rim_touched;
  struct Piece {
    int voxels;
    Eigen::Vector3d sum;  // of its voxels' indices
    Eigen::Vector3i lo, hi;
    bool kept = true;
  };
  std::vector<Piece> pieces;  // its scratch
  std::vector<int> piece_label;
  std::vector<size_t> piece_stack;  // voxels' indices in the occupied box
  std::vector<float> geodesic;      // its scratch, over the occupied box and a border
  std::vector<uint8_t> geodesic_inside;
  std::vector<std::pair<float, int>> geodesic_heap;
  std::vector<Eigen::Vector3d> surface_all, hull;
  // Silhouette distance transforms (cells), per camera; present[c] when this frame has one. Each
  // is computed over the silhouette's bounding box grown by kDtMargin cells (dt_box: x0, y0, x1,
  // y1, inclusive; empty when x1 < x0), where it is exact (no silhouette cell lies outside);
  // every other cell holds kFarCells. About a quarter of the cells at step 4.
  static constexpr int kDtMargin = 16;
  static constexpr float kFarCells = 1000.0f;
  std::vector<std::vector<float>> dt;
  std::vector<Eigen::Array4i> dt_box;
  std::vector<uint8_t> present;
  std::vector<uint8_t> told_empty;  // per camera: said that its silhouette is left out
  // This frame's silhouettes by camera (null where none), while it is tracked.
  std::vector<const LowResSilhouette*> frame_silhouettes;
  // This frame's rays through the silhouettes' edges (sampleRim), every camera's.
  std::vector<RimRay> rim;
  std::vector<double> rim_residuals;  // rimRms's scratch
  std::vector<float> dt_f, dt_d, dt_z, dt_col;
  std::vector<int> dt_v;
  // Body model.
  Skeleton generic;
  Skeleton skeleton;
  BodyShape shape;
  double foot_scale = 1.0;  // the feet's radii over the body's (shoes)
  bool shape_calibrated = false;
  double generic_head_z = 1, generic_top_z = 1, generic_bottom_z = 0;
  std::vector<Capsule> capsules;
  std::vector<Sample> samples;
  // Pairs of capsules that a body keeps apart (an arm and the torso or the head, the two legs'
  // shins and feet), of those apart in the rest pose (makeApartPairs): each no closer than
  // apart_fraction of its radii's sum (flesh and clothes give).
  std::vector<std::pair<int, int>> apart;
  void makeApartPairs();
  std::vector<Dof> dofs;
  std::vector<std::vector<int>> chain;  // dofs moving each joint, ascending
  // Per evaluation.
  std::vector<Eigen::Isometry3d> global;
  std::vector<Eigen::Vector3d> dof_axis, dof_centre;
  std::vector<Eigen::Vector3d> cap_a, cap_b;
  // The capsules that can be nearest to each hull sample (ascending, in candidates from
  // candidate_begin[i]): those within kCandidateMargin of the nearest when the lists were made,
  // with the capsules then at candidate_a, candidate_b. While no capsule end has moved more than
  // half the margin since, no other capsule can be nearest (a segment whose ends move by at most
  // m moves at most m from any point): the fit's iterations look at 2 to 4 capsules a sample
  // instead of all of them, and find the same nearest one.
  static constexpr double kCandidateMargin = 0.10;
  std::vector<uint8_t> candidates, rim_candidates;  // and those of each rim ray
  std::vector<int> candidate_begin, rim_candidate_begin;
  std::vector<double> capsule_distance;  // of one sample to every capsule, while making them
  // The capsules at cap_a, cap_b in bounding spheres: their axes' middles and how far their
  // surfaces reach from them (half the axis and the radius).
  std::vector<Eigen::Vector3d> cap_mid;
  std::vector<double> cap_reach;
  void capsuleSpheres();
  // The distance from `x` to the nearest capsule's surface (cap_a, cap_b, after capsuleSpheres),
  // and into capsule_distance every capsule's within `margin` of it (the others': infinity, or
  // their distance). `hint`: a capsule likely near `x` (the previous sample's nearest), then the
  // nearest. The capsules whose bounding spheres lie further away are never measured: a hull
  // sample lies near 3 or 4 of the body's 28.
  double hullDistances(const Eigen::Vector3d& x, int& hint, double margin);
  // The distance from `ray` to the nearest capsule's surface (cap_a, cap_b), and into
  // capsule_distance every capsule's.
  double rimDistances(const RimRay& ray);
  std::vector<Eigen::Vector3d> candidate_a, candidate_b;
  bool candidates_valid = false;
  Eigen::MatrixXd H, H_new;
  Eigen::VectorXd g, g_new, delta;
  Eigen::MatrixXd damped;
  Eigen::LDLT<Eigen::MatrixXd> ldlt;
  Pose candidate, predicted, fitted;
  // Per joint, the residuals' normal equations in the joint's spatial terms (evaluate): every
  // degree of freedom moves a point p by a x (p - c) (a turn about axis a through c) or by a (a
  // shift), so a residual's Jacobian row over a joint's chain is S_d . w, with S_d = (c x a, a) or
  // (a, 0) and w = (g, p x g) for its slope g = dr/dp. The residuals of a joint add w w^T and
  // w r, and the chain's block of J^T J is S^T M S, once a joint: per residual 36 products
  // instead of one for each pair of the chain's degrees of freedom (up to 24: about 300).
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  std::vector<Eigen::Matrix<double, 6, 6>> joint_m;
  std::vector<Vector6d> joint_g, dof_spatial;
  std::vector<uint8_t> joint_used;
  // Tracking state.
  bool tracking = false;
  int bad_frames = 0;
  int empty_frames = 0;      // in a row: the hull too small for anyone
  bool shape_given = false;  // by setShape(): kept whoever walks on
  Pose pose, previous;
  bool has_previous = false;
  Pose prior_pose;
  bool use_prior = false;
  double prior_weight = 0;

  Impl(const Rig& r, const SkinnedMesh& mesh, const PoseTrackerOptions& o);
  // The constructor's steps. The stage box (narrowed about its centre where it was worked out
  // from the cameras and its tables would not fit), its voxels' grid; refused when the tables
  // still do not fit. `wide`: the cells take 32 bits.
  void sizeStage(bool wide);
  // Every voxel's cell in every camera, and the blocks (makeBlocks).
  void projectVoxels(bool wide);
  // The degrees of freedom (parents first, so that every chain ascends), and the fit's scratch.
  void makeDofs();
  void buildModel(const SkinnedMesh& mesh);
  void setShape(const BodyShape& s);
  void prepareSilhouettes(const std::vector<const LowResSilhouette*>& silhouettes);
  // Appends to `rim` up to `count` rays through silhouette s's edge cells, evenly thinned, each
  // through the cell's edge (half a cell outward from its centre).
  void sampleRim(const LowResSilhouette& s, int count);
  // Leaves out of this frame the camera whose silhouette misses much of the body posed in
  // `global` (the prediction's forward kinematics) while every other camera's holds it: a
  // segmenter's mask that lost the actor's upper body would carve it from the hull. At most one a
  // frame, with four cameras or more. Returns the camera left out, or -1.
  int leaveOutDisagreeingCamera();
  // Carves voxels [lo, hi] (inclusive) and samples the hull's surface; returns the volume.
  // `bottom_z`: the lowest occupied voxel's floor (the floor itself where the actor stands).
  double carve(Eigen::Vector3i lo, Eigen::Vector3i hi, Eigen::Vector3d* centroid, double* top_z,
               double* bottom_z = nullptr);
  // Samples the surface of the occupied voxels (occupied_lo..occupied_hi) into surface_all and
  // hull; voxels lo..hi are the carved region (its border counts as empty).
  void sampleSurface(const Eigen::Vector3i& lo, const Eigen::Vector3i& hi);
  template <typename T>
  void makeBlocks(const std::vector<T>& table);
  // The largest squared distance, in cells of camera c, of the cells of voxels first .. last from
  // the first one's; -1 where the camera does not see one of them.
  template <typename T>
  int blockReach2(const std::vector<T>& table, const Eigen::Vector3i& first,
                  const Eigen::Vector3i& last, int c) const;
  static Eigen::Vector3i blocksOf(const Eigen::Vector3i& voxels) {
    return (voxels.array() + kBlock - 1) / kBlock;
  }
  // The fit's cost of pose `p`, and with `jacobian` its normal equations (h = J^T J, grad =
  // J^T r, over the degrees of freedom).
  double evaluate(const Pose& p, bool jacobian, Eigen::MatrixXd& h, Eigen::VectorXd& grad);
  // evaluate(p, false)'s cost, for a pose seen once (a hypothesis of the initialisation's search):
  // each sample's nearest capsule found among all of them (no candidate lists, which pay only
  // over a fit's iterations), and given up as soon as the cost passes `bound` (what it has summed
  // so far returned: more than `bound`, less than the whole).
  double score(const Pose& p, double bound);
  // evaluate's parts (tracker_fit.cpp). Each degree of freedom's axis and spatial terms for `p`,
  // the joints' sums cleared.
  void prepareJacobian(const Pose& p);
  // Each term's cost added to `cost`, with `jacobian` its residuals' normal equations to the
  // joints' sums (accumulate): the hull's samples on the model's surface, the rays through the
  // silhouettes' edges touching it, the bones' axes inside every silhouette, the parts of the body
  // kept apart.
  void addHullCost(bool jacobian, double& cost);
  // The hull's and the rim's costs' robust terms for a residual `r` (metres).
  double hullTerm(double r) const {
    return tracker_detail::huber(r, r < 0 ? 4 * opt.huber_m : opt.huber_m);
  }
  double rimTerm(double r) const {
    return opt.rim_weight * tracker_detail::huber(r, opt.rim_huber_m);
  }
  void addRimCost(bool jacobian, double& cost);
  void addSilhouetteCost(bool jacobian, double& cost);
  void addApartCost(bool jacobian, double& cost);
  // The joints' sums into the degrees of freedom: S^T M S and S^T g over each joint's chain.
  void sumIntoDofs(Eigen::MatrixXd& h, Eigen::VectorXd& grad) const;
  // The temporal prior toward prior_pose.
  void addPriorCost(const Pose& p, bool jacobian, Eigen::MatrixXd& h, Eigen::VectorXd& grad,
                    double& cost) const;
  // Adds w * J^T J and w * J^T r for a residual whose Jacobian is dr/dp . dp/dtheta, p a point
  // moving with `joint` (in the joint's spatial terms, joint_m and joint_g).
  void accumulate(int joint, const Eigen::Vector3d& point, const Eigen::Vector3d& dr_dp, double r,
                  double w) {
    Vector6d spatial;
    spatial << dr_dp, point.cross(dr_dp);
    joint_m[joint].noalias() += w * spatial * spatial.transpose();
    joint_g[joint] += (w * r) * spatial;
    joint_used[joint] = 1;
  }
  // Places the capsules for the pose in `global` (cap_a, cap_b) and remakes the hull samples'
  // candidate capsules when they no longer hold.
  void placeCapsules();
  // The capsules' axes' ends for the pose in `global`, into `a` and `b` (resized).
  void capsuleEnds(std::vector<Eigen::Vector3d>& a, std::vector<Eigen::Vector3d>& b) const;
  // The nearest capsule to hull sample i (its index, the signed distance to its surface, the
  // closest point on its axis).
  int nearestCapsule(size_t i, double& distance, Eigen::Vector3d& closest) const;
  // The same for rim ray i (the signed distance to its surface, the closest points on the ray and
  // on the capsule's axis).
  int nearestRimCapsule(size_t i, double& distance, Eigen::Vector3d& on_ray,
                        Eigen::Vector3d& on_segment) const;
  // Levenberg-Marquardt from `p` over every degree of freedom but those in dof_held (empty: none
  // held); returns the cost.
  double fit(Pose& p, int iterations);
  std::vector<uint8_t> dof_held;
  // dof_held set so that only `limb`'s joints move.
  void holdAllBut(const tracker_detail::Limb& limb);
  double fitRms(const Pose& p);
  // The rays through the silhouettes' edges to the body's surface (those beyond rim_outlier_m
  // counted at it), RMS over the nearest four fifths, metres: how well the body explains the
  // silhouettes, whatever the number of cameras.
  double rimRms(const Pose& p);
  // Whether a fit with these errors holds the actor (lost_rms_m, lost_rim_m).
  bool fitHolds(double hull_rms, double rim_rms) const {
    return hull_rms <= opt.lost_rms_m && (rim.empty() || rim_rms <= opt.lost_rim_m);
  }
  void apply(Pose& p, const Eigen::VectorXd& delta) const;
  // Limb recovery (limb_recovery.cpp). When many rays through the silhouettes' edges pass far from
  // the body posed in `p`, the hull samples that no capsule explains, into `unexplained`; returns
  // the count of such rays, or 0 when too few of either to recover a limb from.
  int countUnexplained(const Pose& p);
  // The rays through the silhouettes' edges far from the capsules as placed.
  int unexplainedRays() const;
  // After countUnexplained(p) (its `rays`): each limb that can reach much unexplained hull tried
  // there (stretched toward its far end, `iterations` of the fit from there, without the prior);
  // the best kept in `p` when it lowers the fit's cost and explains most of those rays. Returns
  // whether it did.
  bool recoverLimbs(Pose& p, int rays, int iterations);
  std::vector<Eigen::Vector3d> unexplained;
  std::vector<Eigen::Isometry3d> limb_global;
  Pose limb_best, limb_trial;
  int recovery_wait = 0;  // frames before the tracker tries to recover a limb again
  // The constant-velocity prediction from `before` to `now`, damped (velocity_gain), in limits.
  void predictFrom(const Pose& now, const Pose& before, Pose& predicted) const;
  // The turned twin (turned_twin.cpp): after an initialisation (`pose`, its fit's cost
  // `pose_cost`), the pose turned half round and fitted (`iterations`); tracked beside the pose
  // for a few frames unless it fits much worse at once.
  void makeTwin(double pose_cost, int iterations);
  // Each tracked frame after the pose's fit (its cost without the prior, `pose_cost`): the twin
  // fitted from its own prediction; when its frames are done and it fitted better, it becomes the
  // pose (and its previous one). Returns whether it did.
  bool trackTwin(double pose_cost);
  // How far ahead of each ankle (toward its toes, metres, the feet's mean) the hull's samples
  // around that foot lie, for the body in pose `p`: positive when the pose faces the way the
  // actor's feet point.
  double feetAhead(const Pose& p);
  // Whether the twin's toes reach clearly further into the hull's feet than the pose's.
  bool feetFavourTwin();
  Pose twin, twin_previous;
  int twin_frames = 0;  // left to track the twin for; 0: none
  double twin_cost = 0, pose_cost_sum = 0;
  // `volume`: the stage's hull carved for it, m³.
  bool initialise(TrackResult& out, double& volume);
  // The search from the library (initialise's): each pose scaled so that the body spans
  // `top_extent` (the hull's, less the hair) and, where `crown_extent` > 0, its head's top spans
  // that (a crown below raised hands), as upright as the pose or as `fixed_upright` where given;
  // the hypotheses scored, the best fitted, the shape calibrated. Returns whether a body holds;
  // `straighter`: where the hull's length from soles to crown makes the body found clearly
  // straighter than its pose (0 otherwise), that uprightness.
  bool findActor(TrackResult& out, const Eigen::Vector3d& centroid, double bottom_z,
                 double top_extent, double crown_extent, double fixed_upright, double& straighter);
  // The arms placed by appearance (arm_appearance.cpp). This frame's colours, per camera (null:
  // none).
  std::vector<const CellColours*> colours;
  // How differently the cameras that see the body's surface in pose `p` see its colour there
  // (the mean squared spread of its chromaticity about each point's mean, over the points seen
  // by two cameras or more), or -1 without colours in two cameras.
  double colourSpread(const Pose& p);
  // Each arm tried elsewhere (shoulder and elbow turned, the arm then fitted alone, `iterations`,
  // on every `stride`-th sample) and the pose `p` moved to the placement whose surface the
  // cameras see alike, among those that fit the silhouettes nearly as well; `cost` set to its
  // fit's cost. Returns whether it moved.
  bool placeArmsByAppearance(Pose& p, double& cost, int iterations, int stride);
  // placeArmsByAppearance in a frame with colours in two cameras or more (else the arms stay
  // pending), clearing arms_pending; `cost` set to the pose's fit's cost when it ran. Returns
  // whether an arm moved.
  bool placeArmsWhenColoured(Pose& p, double& cost);
  int colouredCameras() const;
  bool arms_pending = false;  // the arms not placed by colours since the actor was found
  // Each arm's trials: fitted this many iterations on every kArmStride-th hull sample and rim ray.
  // 5 on every 8th against 10 on every 4th: the same arms on the development boxers, in half the
  // time; on every 16th, the trials' costs misjudged an arm (docs/figures-history.md).
  static constexpr int kArmIterations = 5, kArmStride = 8;
  Pose arm_trial, arm_best, arm_start;
  std::vector<Eigen::Vector3d> spread_a, spread_b;  // colourSpread's capsule ends
  // Initialisation (tracker_initialisation.cpp). The poses it starts from (makeInitialisationPoses
  // on the generic skeleton), each one's lowest point (the capsules', at the generic shape) and
  // uprightness, and the scratch of its search.
  struct Hypothesis {
    double cost;
    int pose;
    double heading_rad, height_m;
    double upright;  // the body's in that pose, which height_m was scaled by
    bool crown;      // scaled to the crown below raised hands, not the hull's top
  };
  std::vector<Pose> library;
  // library_crown_upright: the poses' uprightness to their heads' tops.
  std::vector<double> library_bottom, library_upright, library_crown_upright;
  std::vector<Hypothesis> hypotheses;
  // The hull's samples and the rim thinned to every `stride`-th (the full sets kept in full_hull
  // and full_rim), until fullSamples() puts them back.
  void thinSamples(int stride);
  void fullSamples();
  std::vector<Eigen::Vector3d> full_hull;
  std::vector<RimRay> full_rim;
  bool thinned = false;
  void makeLibrary();
  // The body model's lowest and highest point (capsules) in pose `p` of the current skeleton.
  // `crown`, where given: its head's highest point.
  void modelExtent(const Pose& p, double& bottom, double& top, double* crown = nullptr);
  // The library pose `i` turned to `heading_rad`, its centre over `centroid` (x, y) and its lowest
  // point at `bottom_z`, for the current skeleton.
  Pose placedLibraryPose(int i, double heading_rad, const Eigen::Vector3d& centroid,
                         double bottom_z);
  // The generic shape scaled so that its body, as upright as `upright`, spans `extent_m`
  // vertically.
  BodyShape shapeSpanning(double extent_m, double upright) const;
  // The coordinate search over the body's proportions from `best_pose` (its cost `best`), for a
  // hull `extent` tall with the body as upright as `upright` (its library pose's); both updated,
  // the shape set.
  // `heavy`: the search again, for a heavy actor (the girth and the belly further).
  void calibrateShape(Pose& best_pose, double extent, double upright, double& best, bool heavy);
  // The body's height taken again from a frame in which the actor stands straighter than in any
  // frame it was taken from (the hull's extent `hull_bottom`..`hull_top` over the model's in the
  // tracked pose): an actor found crouching is measured when he stands up. Moves the pose (and
  // the previous one) so that its lowest point stays where it was.
  void remeasureHeight(double hull_bottom, double hull_top);
  // How straight the body stands in `p`: its extent over its extent at rest (1 standing).
  // `to_crown`: to its head's top, whatever a raised hand reaches.
  double uprightness(const Pose& p, bool to_crown = false);
  double height_uprightness = 0;  // of the frame the height was last taken from
  double rest_extent_m = 1;       // the body's extent at rest, for the current shape (setShape)
  // The height of a shape whose body spans `extent` (crown above its lowest point) standing as
  // straight as `upright` (1 standing) with legs `legs` times the generic ones': the generic mesh's
  // crown scaled.
  double heightSpanning(double extent, double upright, double legs) const;
  Pose rest_pose;
  // The calibrated proportions forgotten: the next initialisation calibrates anew.
  void forgetShape() {
    shape_calibrated = false;
    foot_scale = 1.0;
    height_uprightness = 0;
  }
};

}  // namespace lumistage
