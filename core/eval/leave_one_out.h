#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "core/body/skinned_mesh.h"
#include "core/capture/session_reader.h"
#include "core/eval/view_metrics.h"
#include "core/imaging/clean_plate.h"

namespace lumistage {

// Which masks of the actor a view is scored over: the session's truth (a virtual-studio session),
// else the masks it carries from another tool (masks/), else each image keyed on its green screen
// (the screen learnt from the camera's first scored image).
enum class ScoreMasks { kTruth, kGiven, kKeyed };
ScoreMasks scoreMasksOf(const SessionReader& session);
// Frame i's images, and its masks where the session carries them (CameraFrame::mask): as the
// nodes key it. Throws Error naming the file of a mask that is missing or damaged.
void readFrameWithMasks(const SessionReader& session, int i, std::vector<CameraFrame>& out);
const char* scoreMasksName(ScoreMasks masks);  // "truth", "given", "keyed"

// Leave-one-camera-out over frames of a recorded session. Means over the figures measured: a view
// without the actor (an empty mask) scores nothing over the mask and is left out of them; a figure
// nobody measured is NaN (null in the report).
struct LeaveOneOutSummary {
  std::vector<ViewScore> per_camera;  // mean over the frames (pixels: their sum)
  ViewScore mean;                     // over the cameras' means (pixels: their sum)
  std::vector<ViewScore> per_frame;   // mean over the cameras, frame by frame (of `frames`)
  int frames = 0;
  ScoreMasks masks = ScoreMasks::kTruth;
};

// Which mesh renders a frame's views: one for every camera's view (mesh_for(i, -1)), or one per
// left-out camera (mesh_for(i, c) renders camera c's view only: the strict variant, whose mesh
// never saw camera c's image).
enum class LeaveOneOutMeshes { kOnePerFrame, kOnePerLeftOutCamera };

// Each view as it was scored: frame index, camera, the render (RGBA8), the camera's image (RGBA8)
// and the mask it was scored over, all of the camera's size.
using LeaveOneOutViewSink =
    std::function<void(int frame, int camera, std::span<const uint8_t> rendered,
                       std::span<const uint8_t> truth, std::span<const uint8_t> mask)>;

// For each frame index in `frames`, renders every camera's view from the other cameras on the
// mesh `mesh_for` gives (the truth surface, the posed or the refined mesh; normals set) and
// compares it with the camera's image over the actor's mask (scoreMasksOf, keyed on `plates` where
// a camera has one; null: sessionPlates); `views`, when given, sees every view. Needs a current
// OpenGL context (EglContext). Throws Error naming the file when a mask cannot be read.
LeaveOneOutSummary evaluateLeaveOneOut(const SessionReader& session, const std::vector<int>& frames,
                                       const std::function<TriangleMesh(int, int)>& mesh_for,
                                       LeaveOneOutMeshes meshes = LeaveOneOutMeshes::kOnePerFrame,
                                       const LumigraphParams& params = {},
                                       const LeaveOneOutViewSink& views = {},
                                       const CameraPlates* plates = nullptr);

// The truth surface of frame index i (truth/surface/NNNNNN.ply, normals computed).
TriangleMesh truthSurface(const SessionReader& session, int i);

}  // namespace lumistage
