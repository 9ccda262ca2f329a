#include "core/eval/corpus_eval.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/body/human_skeleton.h"
#include "core/capture/session_reader.h"
#include "core/eval/eval_report.h"
#include "core/sim/virtual_studio.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

constexpr const char* kStageFile = "studio.yaml";

// Whether `folder` holds the session of `text`'s stage with at least `frames` frames.
bool holdsStage(const fs::path& folder, const std::string& text, int frames) {
  std::error_code ec;
  if (!fs::exists(folder / kStageFile, ec)) return false;
  if (readFile(folder / kStageFile) != text) return false;
  try {
    return SessionReader(folder).frameCount() >= frames;
  } catch (const std::exception&) {
    return false;  // a session cut short before its first frame: filmed anew
  }
}

void film(const StudioConfig& config, int frames, const fs::path& folder,
          const std::function<void(int, int)>& progress) {
  std::error_code ec;
  if (fs::exists(folder, ec)) {
    if (!fs::exists(folder / kStageFile, ec))
      throw Error(folder.string() + ": not a corpus stage (no " + kStageFile +
                  "); left as it is, choose another folder");
    fs::remove_all(folder, ec);
    if (ec)
      throw Error(folder.string() + ": cannot remove the stage filmed before: " + ec.message());
  }
  // Filmed into a folder beside, then renamed: a stage folder always holds a whole session.
  fs::path partial = folder;
  partial += ".partial";
  fs::remove_all(partial, ec);
  {
    VirtualStudio studio(config, frames);
    const std::unique_ptr<SessionWriter> writer = openStudioSession(studio, partial);
    StudioFrame frame;
    std::vector<Image> images;
    for (int f = 0; f < frames; ++f) {
      studio.renderFrame(f, frame);
      writeStudioFrame(studio, frame, f, *writer, images);
      if (f == frames / 2) writeContactSheet(config.rig, frame, partial / "contact_sheet.png");
      if (progress) progress(f + 1, frames);
    }
  }
  writeFileAtomically(partial / kStageFile, formatStudioConfig(config, "rig.yaml"));
  fs::rename(partial, folder, ec);
  if (ec)
    throw Error(partial.string() + ": cannot rename to " + folder.string() + ": " + ec.message());
}

double reportNumber(const EvalReport& report, const char* key) {
  const EvalReport::Entry* entry = report.find(key);
  return entry ? entry->number : std::nan("");
}

std::string number(double value, const char* format = "{:.4g}") {
  return std::isfinite(value) ? fmt::format(fmt::runtime(format), value) : "null";
}

struct Summary {
  int stages = 0, untracked = 0, frames = 0, tracked = 0;
  double mpjpe_mean = std::nan(""), mpjpe_worst_stage = std::nan(""),
         mpjpe_worst_frame = std::nan(""), height_error_max_m = std::nan("");
  uint32_t worst_seed = 0;
};

Summary summarise(const std::vector<CorpusStageResult>& stages) {
  Summary s;
  double sum = 0;
  int counted = 0;
  for (const CorpusStageResult& r : stages) {
    ++s.stages;
    s.frames += r.frames;
    s.tracked += r.frames_tracked;
    if (!std::isfinite(r.mpjpe_mm)) {
      ++s.untracked;
      continue;
    }
    sum += r.mpjpe_mm;
    ++counted;
    if (!(r.mpjpe_mm <= s.mpjpe_worst_stage)) {
      s.mpjpe_worst_stage = r.mpjpe_mm;
      s.worst_seed = r.seed;
    }
    if (!(r.mpjpe_mm_max <= s.mpjpe_worst_frame)) s.mpjpe_worst_frame = r.mpjpe_mm_max;
    const double e = std::abs(r.heightErrorM());
    if (!(e <= s.height_error_max_m)) s.height_error_max_m = e;
  }
  if (counted > 0) s.mpjpe_mean = sum / counted;
  return s;
}

}  // namespace

CorpusStageResult evaluateCorpusStage(uint32_t seed, const StageDrawOptions& draw,
                                      const fs::path& folder, const SkinnedMesh& generic,
                                      const MocapEvalOptions& mocap,
                                      const std::function<void(int, int)>& progress) {
  const StudioConfig config = drawStage(seed, draw);
  if (!holdsStage(folder, formatStudioConfig(config, "rig.yaml"), draw.frames))
    film(config, draw.frames, folder, progress);
  const SessionReader session(folder);
  EvalReport report;
  MocapEvalOptions options = mocap;
  options.max_frames = draw.frames;
  evaluateMocap(session, generic, options, report);
  CorpusStageResult r;
  r.seed = seed;
  r.description = describeStage(config);
  r.cameras = config.rig.cameraCount();
  r.actor_height_m = statureOf(config.actor.shape);
  r.tracked_height_m = reportNumber(report, "actor_stature_m");
  r.frames = int(reportNumber(report, "frames"));
  r.frames_tracked = int(reportNumber(report, "frames_tracked"));
  r.mpjpe_mm = reportNumber(report, "mpjpe_mm");
  r.mpjpe_mm_max = reportNumber(report, "mpjpe_mm_max");
  r.pose_ms = reportNumber(report, "pose_ms");
  r.init_ms = reportNumber(report, "init_ms");
  return r;
}

std::string corpusJson(const std::vector<CorpusStageResult>& stages) {
  const Summary s = summarise(stages);
  std::string out = "{\n  \"summary\": {";
  out += fmt::format(
      "\"stages\": {}, \"stages_untracked\": {}, \"frames\": {}, \"frames_tracked\": {}, "
      "\"frames_tracked_pct\": {}, \"mpjpe_mm\": {}, \"mpjpe_mm_worst_stage\": {}, "
      "\"worst_stage_seed\": {}, \"mpjpe_mm_worst_frame\": {}, \"height_error_cm_max\": {}}},\n",
      s.stages, s.untracked, s.frames, s.tracked,
      number(s.frames > 0 ? 100.0 * s.tracked / s.frames : std::nan("")), number(s.mpjpe_mean),
      number(s.mpjpe_worst_stage), std::isfinite(s.mpjpe_worst_stage) ? s.worst_seed : 0,
      number(s.mpjpe_worst_frame), number(100 * s.height_error_max_m));
  out += "  \"stages\": [";
  for (size_t i = 0; i < stages.size(); ++i) {
    const CorpusStageResult& r = stages[i];
    std::string description;
    for (char c : r.description) description += (c == '"' || c == '\\') ? '_' : c;
    out += fmt::format(
        "{}\n    {{\"seed\": {}, \"stage\": \"{}\", \"cameras\": {}, \"actor_height_m\": {}, "
        "\"tracked_height_m\": {}, \"frames\": {}, \"frames_tracked\": {}, \"mpjpe_mm\": {}, "
        "\"mpjpe_mm_max\": {}, \"pose_ms\": {}, \"init_ms\": {}}}",
        i ? "," : "", r.seed, description, r.cameras, number(r.actor_height_m),
        number(r.tracked_height_m), r.frames, r.frames_tracked, number(r.mpjpe_mm),
        number(r.mpjpe_mm_max), number(r.pose_ms), number(r.init_ms));
  }
  out += "\n  ]\n}\n";
  return out;
}

std::string corpusTable(const std::vector<CorpusStageResult>& stages) {
  const auto cell = [](double v, const char* format) {
    return std::isfinite(v) ? fmt::format(fmt::runtime(format), v) : std::string("-");
  };
  std::string out = fmt::format("{:>6} {:>4} {:>7} {:>9} {:>8} {:>8} {:>9}  {}\n", "seed", "cams",
                                "actor", "tracked", "MPJPE", "worst", "height", "stage");
  for (const CorpusStageResult& r : stages)
    out += fmt::format("{:>6} {:>4} {:>6.2f}m {:>4}/{:<4} {:>8} {:>8} {:>9}  {}\n", r.seed,
                       r.cameras, r.actor_height_m, r.frames_tracked, r.frames,
                       cell(r.mpjpe_mm, "{:.1f}mm"), cell(r.mpjpe_mm_max, "{:.1f}mm"),
                       cell(100 * r.heightErrorM(), "{:+.1f}cm"), r.description);
  const Summary s = summarise(stages);
  out += fmt::format(
      "{} stages: MPJPE mean {} (the stages' means), worst stage {} (seed {}), worst frame {}; "
      "frames tracked {}; height error up to {}; never tracked: {}\n",
      s.stages, cell(s.mpjpe_mean, "{:.1f} mm"), cell(s.mpjpe_worst_stage, "{:.1f} mm"),
      s.worst_seed, cell(s.mpjpe_worst_frame, "{:.1f} mm"),
      cell(s.frames > 0 ? 100.0 * s.tracked / s.frames : std::nan(""), "{:.1f} %"),
      cell(100 * s.height_error_max_m, "{:.1f} cm"), s.untracked);
  return out;
}

}  // namespace lumistage
