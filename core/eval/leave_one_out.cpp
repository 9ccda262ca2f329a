#include "core/eval/leave_one_out.h"

#include <fmt/format.h>

#include "core/body/ply_mesh.h"
#include "core/render/frame_inputs.h"

namespace lumistage {

namespace {

// Adds `weight` x a score's figures to a mean, and its pixels to the sum.
void addScore(ViewScore& mean, const ViewScore& s, double weight) {
  mean.psnr_db += weight * s.psnr_db;
  mean.ssim += weight * s.ssim;
  mean.matte_psnr_db += weight * s.matte_psnr_db;
  mean.missed_pct += weight * s.missed_pct;
  mean.beyond_pct += weight * s.beyond_pct;
  mean.pixels += s.pixels;
}

}  // namespace

TriangleMesh truthSurface(const SessionReader& session, int i) {
  return readPlyMesh(session.folder() / "truth" / "surface" /
                     fmt::format("{:06}.ply", session.frameId(i)));
}

LeaveOneOutSummary evaluateLeaveOneOut(const SessionReader& session, const std::vector<int>& frames,
                                       const std::function<TriangleMesh(int, int)>& mesh_for,
                                       LeaveOneOutMeshes meshes, const LumigraphParams& params) {
  const Rig& rig = session.rig();
  const int n = rig.cameraCount();
  std::vector<int> all(n);
  for (int c = 0; c < n; ++c) all[c] = c;
  LumigraphRenderer renderer(rig, all, params);
  LeaveOneOutSummary summary;
  summary.per_camera.resize(n);
  std::vector<CameraFrame> images;
  std::vector<std::vector<uint8_t>> truth(n), masks(n);
  FrameInputs inputs;  // images and foreground masks, as the nodes give theirs
  for (int i : frames) {
    session.readFrame(i, images);
    inputs.set(renderer, images);
    for (int c = 0; c < n; ++c) {
      imageToRgba(images[c].image.view(), truth[c]);
      masks[c] = session.readTruthMask(c, i);
    }
    std::vector<ViewScore> scores;
    if (meshes == LeaveOneOutMeshes::kOnePerFrame) {
      const TriangleMesh mesh = mesh_for(i, -1);
      renderer.setMesh(mesh.positions, mesh.normals, mesh.triangles);
      scores = leaveOneOut(renderer, rig, truth, masks);
    } else {
      for (int c = 0; c < n; ++c) {
        const TriangleMesh mesh = mesh_for(i, c);
        renderer.setMesh(mesh.positions, mesh.normals, mesh.triangles);
        scores.push_back(leaveOneOut(renderer, rig, truth, masks, c));
      }
    }
    for (int c = 0; c < n; ++c) addScore(summary.per_camera[c], scores[c], 1.0 / frames.size());
    ++summary.frames;
  }
  for (const ViewScore& s : summary.per_camera) addScore(summary.mean, s, 1.0 / n);
  return summary;
}

}  // namespace lumistage
