#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <vector>

#include "core/body/human_skeleton.h"
#include "core/body/skinned_mesh.h"
#include "core/geometry/rig.h"
#include "core/imaging/cell_colours.h"
#include "core/imaging/silhouettes.h"

namespace lumistage {

struct PoseTrackerOptions {
  // The nodes' LowResSilhouette step and the hull's grid. Step 4 and 2 cm against step 8 and 3 cm:
  // MPJPE 19.0 / 27.1 / 19.4 / 24.1 -> 18.9 / 25.7 / 20.6 / 20.9 mm (walk / arm wave / turn /
  // crouch), the worst frame of each 26 / 32 / 26 / 26 mm against 24 / 37 / 26 / 52, for 14 ms a
  // tracked frame against 6 (tracking_bench; docs/lumigraph.md). 2.5 cm and 2.25 cm: lower means
  // on some clips, but a lost frame on the turn and the arm wave's arm lost for good. (Measured
  // with each cell keyed by its centre pixel; keyed by the 3x3 pixels around it, keyCell, step 4
  // gave 15.2 / 20.1 / 14.9 / 16.8 mm on 40-frame clips, 14.8 / 18.4 / 13.4 / 16.0 mm once the
  // girth stopped lengthening the capsules.)
  int silhouette_step = 4;
  double voxel_m = 0.02;
  // The box carved for the actor: empty, the rig's (stageVolume: the rig file's stage, else the
  // floor the cameras cover). Its lookup tables take 2 bytes a voxel and camera (4 for cameras of
  // a megapixel and more) and 5 a block of 4x4x4 voxels and camera: 114 MB for the reference rig's
  // 4.0 x 4.0 x 2.4 m; a box that needs more than max_table_bytes is refused; one worked out from
  // the cameras is narrowed about its centre (down to the default floor) until they fit, and the
  // log says so.
  std::optional<StageBox> stage;
  // `stage` was worked out from the cameras by the caller (stageVolume, for a rig file without
  // one): narrowed as the tracker's own would be, not refused.
  bool stage_from_cameras = false;
  size_t max_table_bytes = size_t(1) << 30;
  int iterations = 10;         // Levenberg-Marquardt iterations per tracked frame
  double velocity_gain = 0.8;  // of the constant-velocity prediction (0: the previous pose)
  int init_iterations = 20;    // per initialisation hypothesis fitted in full
  // Hull surface samples per frame, evenly thinned beyond: one actor's hull has about 2000 surface
  // voxels at 3 cm, all of them kept (at 2 cm, 2.25 times as many by area: thinned to this; to
  // 2500, with 8 iterations, the arm wave lost the arm). Thinned to 1200, a raised arm kept too few
  // samples to hold it: MPJPE 36 -> 28 mm on the arm wave, for about 2.5 ms more a frame.
  int max_hull_points = 4000;
  // Of a sample's silhouette residual (metres) per camera. 1.0 against 0.5: MPJPE lower on all four
  // reference clips, with 12 and with 6 cameras (20.7 against 21.3 mm on average with 12); from
  // 1.5 on, the arm wave loses the arm (38 mm).
  double silhouette_weight = 1.0;
  double prior_weight = 0.2;  // temporal prior, per radian² (per m² for the root)
  // The rim term: rays through the silhouettes' edges, which the body's surface must touch (a
  // silhouette covered by the body, measured in the image rather than on the hull, whose phantom
  // volumes grow as cameras get fewer). Its weight per ray (0: off), the rays a frame (shared by
  // the cameras, at least min_rim_rays_per_camera each), its Huber scale, and the distance beyond
  // which a ray is taken for a part of the silhouette no body explains (a bag, a shadow). Weight 3
  // against 0 on the development corpus (seeds 1-20, 30 frames): MPJPE 24.7 -> 21.5 mm with every
  // camera, 33.1 -> 26.5 with 6, 69.9 -> 37.6 with 4 (tracked frames 85 -> 69 %: the hull's error
  // grows as the body fits the silhouettes closer); 10: 22.2 mm, more frames far off.
  double rim_weight = 3.0;
  int rim_rays = 600;
  int min_rim_rays_per_camera = 40;
  double rim_huber_m = 0.02;
  double rim_outlier_m = 0.25;
  // Parts of the body that cannot pass through each other (an arm and the torso or the head, the
  // shins and feet of the two legs): the weight of their capsules' overlap beyond apart_fraction of
  // their radii's sum, per m² (0: off). Silhouettes cannot tell a forearm inside the torso's
  // outline from one in front of it: a short clothed actor's forearms sank into his chest (wrists
  // 117 mm off; 43 with it). A limb found on the wrong side of the body is held there too. 100
  // against 0: the development corpus 26.1 -> 25.0 mm, the held-out one unchanged (28.9 mm; with
  // 4-6 cameras 34.8 -> 33.7), the boxing development stages 38.3 -> 46.4 mm (two of eleven lose
  // an arm: 46 -> 93 and 57 -> 103 mm). 30: 27.9 and 1000: 30.0 on twelve development stages
  // (29.3 without); a fraction of 0.6 never acts (docs/figures-history.md).
  double apart_weight = 100;
  double apart_fraction = 0.8;
  double huber_m = 0.02;        // robust loss of hull samples outside the model (4x inside)
  double min_volume_m3 = 0.02;  // less hull than this: nobody on stage
  // More hull than this is not a person (a keyer that takes the screen for the actor, the lights
  // gone): nobody is tracked, and no time goes into fitting a body to it. One actor's hull is
  // about 0.1 m³ with 12 cameras.
  double max_volume_m3 = 1.0;
  double lost_rms_m = 0.05;     // hull fit error above this, or
  double lost_rim_m = 0.03;     // silhouette edge error (rimRms) above this...
  int lost_frames = 3;          // ...for this many frames in a row: lost, re-initialise
  bool calibrate_shape = true;  // scale the generic skeleton to the actor at initialisation
  // How far the hull's top stands above the generic human's bald crown, which the calibration
  // takes the body's size from: hair (1 cm on the virtual studio's actor; 0 for a bald head or a
  // tight cap) and the hull carved about a round head. 2 cm against 0: the calibrated pelvis 0.7
  // against 2.4 cm above the actor's, the head 0.5 cm low against 1.5 cm high, and MPJPE 14.8 /
  // 18.4 / 13.4 / 16.0 -> 13.9 / 16.6 / 12.7 / 15.1 mm on the four reference clips (walk / arm
  // wave / turn / crouch; docs/eval-report.md). The legs took the difference: too long, they put
  // a standing actor's ankles 2 cm under the actor's.
  double hair_m = 0.02;
  // An empty stage for this many frames in a row (2 s at 30 fps): the actor has gone, and the
  // next one who walks on is calibrated anew instead of keeping the first one's proportions.
  int forget_shape_after_empty_frames = 60;
  bool track_clavicles = false;  // fit the clavicles' angles too (else they stay at rest)
  // With the cameras' colours (track's `colours`): at initialisation, each arm tried elsewhere
  // (its shoulder and elbow turned, then fitted) and moved where the body's surface looks the
  // same from every camera that sees it, among the placements the silhouettes allow. Silhouettes
  // cannot tell a forearm held before the chest from one across the belly; colours can.
  bool arm_appearance = true;
};

enum class TrackState { kNoActor, kInitialised, kTracking, kLost };

struct TrackResult {
  TrackState state = TrackState::kNoActor;
  bool valid() const { return state == TrackState::kInitialised || state == TrackState::kTracking; }
  Pose pose;                            // of skeleton() (the calibrated one)
  std::vector<Eigen::Vector3d> joints;  // world positions, metres
  double fit_rms_m = 0;                 // hull samples to the model's surface
  double rim_rms_m = 0;                 // silhouette edges to the model's surface (rimRms)
  int hull_points = 0;
  // A camera left out of this frame: its silhouette missed much of the body that every other
  // camera held (a segmenter's mask that lost part of the actor); -1: none.
  int left_out_camera = -1;
};

// Markerless motion capture from every camera's low-resolution silhouette (DESIGN.md §2): each
// frame the visual hull is carved on a fine voxel grid around the previous pose (precomputed
// voxel -> cell lookups), its surface voxels are sampled, and a body model of capsules hung on the
// skeleton's bones (radii measured on the generic mesh) is fitted to them by Levenberg-Marquardt
// over the pose (root translation and rotation, every joint's Euler angles within its box
// limits), with analytic Jacobians and four terms: hull samples on the model's surface (Huber),
// rays through every silhouette's edge touching the model's surface (the rim: the silhouettes
// covered, measured in the images, where the hull's phantom volumes grow as the cameras get
// fewer), the bones' axis samples inside every silhouette (a distance transform of each
// silhouette), and a temporal prior toward the constant-velocity prediction. A camera whose
// silhouette misses much of the predicted body while every other camera's holds it (a
// segmenter's mask that lost part of the actor) is left out of that frame. A limb the fit left
// where the actor's is not (an arm at the side while both hands are over the head: a local
// minimum, the hull there pulling toward the other arm) is recovered where many silhouette edges
// and hull samples are explained by no body part: each limb that reaches that hull is stretched
// toward its far end and fitted alone, and the best kept when it lowers the cost and explains most
// of those edges (at initialisation, and in tracking at most every tenth frame after a try that
// found nothing). Silhouettes barely tell an actor's front from his back: for eight frames after
// each initialisation the pose turned half round is tracked too, and replaces the pose when it
// fitted better over them. Silhouettes cannot tell a forearm held before the chest from one
// across the belly either: with the cameras' colours (every few frames, from the nodes), each arm
// of the pose just found is tried elsewhere and kept where the cameras see the body's surface
// most alike (arm_appearance.cpp).
//
// Initialisation: when nobody is tracked, the whole stage is carved; a hull tall and large enough
// is tried against every pose of a library (makeInitialisationPoses: the built-in clips' poses,
// their mirror images and each bent forward at the hips: crouching, walking, waving, turning,
// bending over, T- and A-pose; and sitting on the floor) at eight headings, over the hull's
// centroid and standing on its lowest point (a hull under 0.6 m high is no one), the body scaled
// (until calibrated) so that it spans the hull's height in that pose; the hypotheses are scored on
// an eighth of the hull and of the rim, the best six fitted in full, and the best fit wins. No
// T-pose is needed. Once per actor (again after the stage stood empty for
// forget_shape_after_empty_frames) the body shape is calibrated: the generic skeleton's bones
// scaled to the hull's extent less hair_m in the pose found (as upright as that pose, or as the
// hull's shortest path from the soles to the crown says where that is less: a boxer's bent knees
// found in a standing pose), then the legs' length (the extent held), the capsules' girth and the
// feet's radius (shoes) by a coordinate search that refits the pose for each trial; a heavy actor
// whose fit that leaves above lost_rms_m gets a second search (the girth further, and the belly).
// An actor found crouching or bent is measured again when he stands straighter (his height from the
// hull's extent in that frame), until he stands straight.
// The arms keep the generic proportions: searching them too lowered the fit's cost but not the
// joints' error. The clavicles stay at rest (track_clavicles). A fit error above lost_rms_m (the
// hull) or lost_rim_m (the rim) for lost_frames frames, or an empty stage, loses the actor; the
// next frames re-initialise by the same search. No ground truth at run time. Not thread-safe;
// reuses its buffers (no allocation per tracked frame once warm).
class PoseTracker {
 public:
  // `generic`: the generic human (makeHumanSkeleton's joints), whose mesh gives the bones' radii.
  // Throws std::invalid_argument for a stage box whose tables would pass max_table_bytes.
  PoseTracker(const Rig& rig, const SkinnedMesh& generic, PoseTrackerOptions options = {});
  const StageBox& stage() const;  // the box it carves
  ~PoseTracker();
  PoseTracker(const PoseTracker&) = delete;
  PoseTracker& operator=(const PoseTracker&) = delete;

  // One frame. `silhouettes`: any subset of the rig's cameras (null entries are skipped).
  // `colours`: the actor's colours in some of those cameras (sampleCellColours; none: the fit
  // goes by the silhouettes alone).
  const TrackResult& track(const std::vector<const LowResSilhouette*>& silhouettes,
                           const std::vector<const CellColours*>& colours = {});
  // Whether the next frame's colours would be used (the arms not yet placed by them since the
  // actor was found): a caller may lay them out only then.
  bool wantsColours() const;
  // Forget the actor (and the calibrated shape): the next frame initialises.
  void reset();
  // Use a known body shape (from an earlier session): no calibration at the next initialisation.
  void setShape(const BodyShape& shape);

  const TrackResult& last() const { return result_; }
  const Skeleton& skeleton() const;  // the generic one scaled to the actor
  const BodyShape& shape() const;
  const PoseTrackerOptions& options() const { return options_; }

  // The tracker's workings (core/tracking/pose_tracker_impl.h): named here so that the tests of
  // its parts can build one; nothing outside core/tracking uses it.
  struct Impl;

 private:
  PoseTrackerOptions options_;
  Impl* impl_;
  TrackResult result_;
};

}  // namespace lumistage
