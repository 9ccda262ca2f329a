#pragma once

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/body/skinned_mesh.h"
#include "core/eval/mocap_eval.h"
#include "core/sim/stage_draw.h"

namespace lumistage {

// One stage of a randomised corpus (drawStage) and how motion capture did on it.
struct CorpusStageResult {
  uint32_t seed = 0;
  std::string description;  // describeStage
  int cameras = 0;
  // How tall the actor stands (statureOf): the truth, and the tracker's calibrated body (NaN:
  // never tracked).
  double actor_height_m = 0;
  double tracked_height_m = std::nan("");
  int frames = 0, frames_tracked = 0;
  double mpjpe_mm = std::nan(""), mpjpe_mm_max = std::nan("");  // NaN: never tracked
  double pose_ms = std::nan(""), init_ms = std::nan("");

  double heightErrorM() const { return tracked_height_m - actor_height_m; }
};

// Films the stage of `seed` (StageDrawOptions) into `folder` as a session (lumistage synth's, with
// the drawn studio config beside it as studio.yaml), unless `folder` already holds that stage's
// session, and evaluates motion capture on it (evaluateMocap, `mocap`). A folder that holds another
// stage (its studio.yaml differs, or too few frames) is filmed anew; a folder without a studio.yaml
// is never touched (Error). `progress(done, total)` follows the filming's frames.
CorpusStageResult evaluateCorpusStage(uint32_t seed, const StageDrawOptions& draw,
                                      const std::filesystem::path& folder,
                                      const SkinnedMesh& generic, const MocapEvalOptions& mocap,
                                      const std::function<void(int, int)>& progress = {});

// The corpus's figures: each stage's, then over all of them the mean of the stages' MPJPE, the
// worst stage's and the worst frame's, the share of frames tracked, the largest height error and
// the stages never tracked. JSON: {"summary": {...}, "stages": [{...}, ...]}, NaN as null.
std::string corpusJson(const std::vector<CorpusStageResult>& stages);
std::string corpusTable(const std::vector<CorpusStageResult>& stages);

}  // namespace lumistage
