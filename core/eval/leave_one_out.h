#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "core/body/skinned_mesh.h"
#include "core/capture/session_reader.h"
#include "core/eval/view_metrics.h"

namespace lumistage {

// Leave-one-camera-out over frames of a recorded virtual-studio session (it needs truth masks).
// Means over the figures measured: a view without the actor (an empty mask) scores nothing over
// the mask and is left out of them; a figure nobody measured is NaN (null in the report).
struct LeaveOneOutSummary {
  std::vector<ViewScore> per_camera;  // mean over the frames (pixels: their sum)
  ViewScore mean;                     // over the cameras' means (pixels: their sum)
  int frames = 0;
};

// Which mesh renders a frame's views: one for every camera's view (mesh_for(i, -1)), or one per
// left-out camera (mesh_for(i, c) renders camera c's view only: the strict variant, whose mesh
// never saw camera c's image).
enum class LeaveOneOutMeshes { kOnePerFrame, kOnePerLeftOutCamera };

// Each view as it was scored: frame index, camera, the render (RGBA8), the camera's image (RGBA8)
// and its truth mask, all of the camera's size.
using LeaveOneOutViewSink =
    std::function<void(int frame, int camera, std::span<const uint8_t> rendered,
                       std::span<const uint8_t> truth, std::span<const uint8_t> mask)>;

// For each frame index in `frames`, renders every camera's view from the other cameras on the
// mesh `mesh_for` gives (the truth surface, the posed or the refined mesh; normals set) and
// compares it with the camera's image over its truth mask; `views`, when given, sees every view.
// Needs a current OpenGL context (EglContext). Throws Error naming the file when a mask cannot be
// read.
LeaveOneOutSummary evaluateLeaveOneOut(const SessionReader& session, const std::vector<int>& frames,
                                       const std::function<TriangleMesh(int, int)>& mesh_for,
                                       LeaveOneOutMeshes meshes = LeaveOneOutMeshes::kOnePerFrame,
                                       const LumigraphParams& params = {},
                                       const LeaveOneOutViewSink& views = {});

// The truth surface of frame index i (truth/surface/NNNNNN.ply, normals computed).
TriangleMesh truthSurface(const SessionReader& session, int i);

}  // namespace lumistage
