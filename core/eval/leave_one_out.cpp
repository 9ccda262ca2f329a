#include "core/eval/leave_one_out.h"

#include <fmt/format.h>

#include "core/body/ply_mesh.h"
#include "core/render/frame_inputs.h"

namespace lumistage {

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
    for (int c = 0; c < n; ++c) {
      summary.per_camera[c].psnr_db += scores[c].psnr_db / frames.size();
      summary.per_camera[c].ssim += scores[c].ssim / frames.size();
      summary.per_camera[c].pixels += scores[c].pixels;
      summary.per_camera[c].matte_psnr_db += scores[c].matte_psnr_db / frames.size();
      summary.per_camera[c].missed_pct += scores[c].missed_pct / frames.size();
      summary.per_camera[c].beyond_pct += scores[c].beyond_pct / frames.size();
    }
    ++summary.frames;
  }
  for (const ViewScore& s : summary.per_camera) {
    summary.psnr_db += s.psnr_db / n;
    summary.ssim += s.ssim / n;
    summary.matte_psnr_db += s.matte_psnr_db / n;
    summary.missed_pct += s.missed_pct / n;
    summary.beyond_pct += s.beyond_pct / n;
  }
  return summary;
}

}  // namespace lumistage
