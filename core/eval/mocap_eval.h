#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <vector>

#include "core/body/skinned_mesh.h"
#include "core/capture/session_reader.h"
#include "core/eval/eval_report.h"
#include "core/imaging/clean_plate.h"
#include "core/tracking/pose_tracker.h"

namespace lumistage {

struct MocapEvalOptions {
  int silhouette_step = 4;  // as the nodes send
  int camera_count = 0;     // use this many of the rig's cameras, evenly spread; 0: all
  int max_frames = 0;       // 0: every readable frame
  // Where to write a picture of the fit (writeFitPicture, <frame>.png) every picture_every
  // frames; empty: none.
  std::filesystem::path pictures;
  int picture_every = 1;
  PoseTrackerOptions tracker;
  // The cameras' clean plates (null: sessionPlates), which key a stage without a green screen.
  const CameraPlates* plates = nullptr;
};

// The tracked motion of a session, frame by frame (what later stages of the evaluation use).
struct MocapEvalResult {
  std::vector<bool> valid;                           // the tracker had the actor
  std::vector<Pose> poses;                           // of `skeleton`
  std::vector<std::vector<Eigen::Vector3d>> joints;  // world, metres
  Skeleton skeleton;                                 // calibrated to the actor
};

// Replays a session as the studio sees it: every camera's image keyed at low resolution
// (GreenScreenKeyer at the cells' centres, as CameraNode does; the session's own masks where it
// carries them), the silhouettes fed to a PoseTracker (its capsules from
// trackingModelFor(generic)), `generic` (the generic human or a file's body) posed as the nodes
// pose it compared with each silhouette (silhouette_iou, per camera silhouette_iou_<camera>: the
// cells of both over the cells of either, mean over tracked frames), and the tracked joints
// compared with truth/joints.csv when the session has it.
// Adds section "mocap" to `report`: frames, frames_tracked, cameras, mpjpe_mm (mean over tracked
// frames of the mean per-joint error), mpjpe_mm_max (the worst frame after initialisation),
// mpjpe_mm_p95, pose_ms (mean CPU time of the fit per tracked frame, on one core; initialising
// frames excluded), pose_ms_max, pose_wall_ms (mean wall time, every frame), init_ms (the longest
// initialising frame), actor_height_m; and per-frame columns pose_ms, tracked, fit_rms_mm,
// mpjpe_mm. Throws Error on unreadable files.
MocapEvalResult evaluateMocap(const SessionReader& session, const SkinnedMesh& generic,
                              const MocapEvalOptions& options, EvalReport& report);

}  // namespace lumistage
