#include "core/eval/leave_one_out.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "core/base/error.h"
#include "core/body/ply_mesh.h"
#include "core/imaging/clean_plate.h"
#include "core/imaging/keyer.h"
#include "core/render/frame_inputs.h"

namespace lumistage {

namespace {

// The mean of scores, figure by figure over those measured (a view without the actor has none
// over the mask: NaN, left out rather than averaged as 0), NaN where none is; pixels summed.
class ScoreMean {
 public:
  void add(const ViewScore& s) {
    const double v[kFigures] = {s.psnr_db,    s.ssim,       s.matte_psnr_db,
                                s.missed_pct, s.beyond_pct, s.missed_error_pct};
    for (int k = 0; k < kFigures; ++k) {
      if (!std::isfinite(v[k])) continue;
      sum_[k] += v[k];
      ++count_[k];
    }
    pixels_ += s.pixels;
  }
  ViewScore mean() const {
    double m[kFigures];
    for (int k = 0; k < kFigures; ++k)
      m[k] = count_[k] > 0 ? sum_[k] / count_[k] : std::numeric_limits<double>::quiet_NaN();
    ViewScore s;
    s.psnr_db = m[0], s.ssim = m[1], s.matte_psnr_db = m[2], s.missed_pct = m[3],
    s.beyond_pct = m[4], s.missed_error_pct = m[5], s.pixels = pixels_;
    return s;
  }

 private:
  static constexpr int kFigures = 6;
  double sum_[kFigures] = {};
  int count_[kFigures] = {};
  int64_t pixels_ = 0;
};

}  // namespace

void readFrameWithMasks(const SessionReader& session, int i, std::vector<CameraFrame>& out) {
  session.readFrame(i, out);
  if (!session.hasMasks()) return;
  std::vector<std::string> errors;
  session.readMasks(i, out, errors);
  for (const std::string& e : errors)
    if (!e.empty()) throw Error(e);
}

ScoreMasks scoreMasksOf(const SessionReader& session) {
  return session.hasTruth()   ? ScoreMasks::kTruth
         : session.hasMasks() ? ScoreMasks::kGiven
                              : ScoreMasks::kKeyed;
}

const char* scoreMasksName(ScoreMasks masks) {
  switch (masks) {
    case ScoreMasks::kTruth:
      return "truth";
    case ScoreMasks::kGiven:
      return "given";
    case ScoreMasks::kKeyed:
      break;
  }
  return "keyed";
}

TriangleMesh truthSurface(const SessionReader& session, int i) {
  return readPlyMesh(session.folder() / "truth" / "surface" /
                     fmt::format("{:06}.ply", session.frameId(i)));
}

LeaveOneOutSummary evaluateLeaveOneOut(const SessionReader& session, const std::vector<int>& frames,
                                       const std::function<TriangleMesh(int, int)>& mesh_for,
                                       LeaveOneOutMeshes meshes, const LumigraphParams& params,
                                       const LeaveOneOutViewSink& views,
                                       const CameraPlates* given_plates) {
  const Rig& rig = session.rig();
  const int n = rig.cameraCount();
  std::vector<int> all(n);
  for (int c = 0; c < n; ++c) all[c] = c;
  LumigraphRenderer renderer(rig, all, params);
  LeaveOneOutSummary summary;
  summary.masks = scoreMasksOf(session);
  std::vector<GreenScreenKeyer> keyers(summary.masks == ScoreMasks::kKeyed ? n : 0);
  const CameraPlates plates = platesOf(session, given_plates);
  bool keyers_learnt = false;
  std::vector<ScoreMean> per_camera(n);
  std::vector<CameraFrame> images;
  std::vector<std::vector<uint8_t>> truth(n), masks(n);
  std::vector<uint8_t> rendered;
  FrameInputs inputs;  // images and foreground masks, as the nodes give theirs
  inputs.setPlates(plates);
  for (int i : frames) {
    readFrameWithMasks(session, i, images);
    inputs.set(renderer, images);
    for (int c = 0; c < n; ++c) {
      const ImageView image = images[c].image.view();
      imageToRgba(image, truth[c]);
      switch (summary.masks) {
        case ScoreMasks::kTruth:
          masks[c] = session.readTruthMask(c, i);
          break;
        case ScoreMasks::kGiven:  // read with the frame (readFrameWithMasks), given to the renderer
          masks[c].swap(images[c].mask);
          break;
        case ScoreMasks::kKeyed:
          if (!keyers_learnt) keyers[c].learnScreen(image);
          masks[c].resize(size_t(image.width) * image.height);
          for (int y = 0; y < image.height; ++y)
            for (int x = 0; x < image.width; ++x)
              masks[c][size_t(y) * image.width + x] = plates[c]
                                                          ? plates[c]->isForeground(image, x, y)
                                                          : keyers[c].isForeground(image, x, y);
          break;
      }
    }
    keyers_learnt = true;
    std::vector<ViewScore> scores;
    const bool mesh_per_camera = meshes == LeaveOneOutMeshes::kOnePerLeftOutCamera;
    for (int c = 0; c < n; ++c) {
      if (c == 0 || mesh_per_camera) {
        const TriangleMesh mesh = mesh_for(i, mesh_per_camera ? c : -1);
        renderer.setMesh(mesh.positions, mesh.normals, mesh.triangles);
      }
      scores.push_back(leaveOneOut(renderer, rig, truth, masks, c, &rendered));
      if (views) views(i, c, rendered, truth[c], masks[c]);
    }
    ScoreMean frame;
    for (int c = 0; c < n; ++c) {
      per_camera[c].add(scores[c]);
      frame.add(scores[c]);
    }
    summary.per_frame.push_back(frame.mean());
    ++summary.frames;
  }
  // Each camera's mean over its frames, then their mean (no frame scored: every figure NaN).
  ScoreMean mean;
  for (const ScoreMean& c : per_camera) {
    summary.per_camera.push_back(c.mean());
    mean.add(summary.per_camera.back());
  }
  summary.mean = mean.mean();
  return summary;
}

}  // namespace lumistage
