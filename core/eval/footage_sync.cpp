// Offsets between unsynchronised cameras from the agreement of their masks through the visual hull
// (footage_sync.h): the masks loaded at a low resolution, the actor's box found on a coarse
// hull, then each free camera's offset tried in turn (coordinate descent) on a fine one.
#include "core/eval/footage_sync.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <stdexcept>

#include "core/base/error.h"
#include "core/capture/footage_import.h"
#include "core/geometry/stage_volume.h"
#include "core/imaging/silhouettes.h"
#include "core/tracking/visual_hull_locator.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

// A camera's masks by footage frame, as silhouettes of one step.
using MaskFrames = std::map<int, LowResSilhouette>;

// The footage frame a mask file is of: its name's digits ("000042.png"); none for other files.
std::optional<int> maskFrame(const fs::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  const std::string stem = file.stem().string();
  if (ext != ".png" || stem.empty() || stem.size() > 9 ||
      !std::all_of(stem.begin(), stem.end(), [](char ch) { return ch >= '0' && ch <= '9'; }))
    return std::nullopt;
  return std::stoi(stem);
}

// Every camera's mask files by frame; throws Error for a camera without any.
std::vector<std::map<int, fs::path>> maskFiles(const Rig& rig, const fs::path& masks) {
  std::vector<std::map<int, fs::path>> files(size_t(rig.cameraCount()));
  for (int c = 0; c < rig.cameraCount(); ++c) {
    const fs::path folder = masks / rig.camera(c).name();
    std::error_code ec;
    if (fs::is_directory(folder, ec))
      for (const fs::directory_entry& entry : fs::directory_iterator(folder, ec))
        if (const std::optional<int> frame = maskFrame(entry.path());
            frame && entry.is_regular_file(ec))
          files[size_t(c)][*frame] = entry.path();
    if (files[size_t(c)].empty())
      throw Error(fmt::format("{}: no masks of camera '{}' (expected FFFFFF.png, by frame)",
                              folder.string(), rig.camera(c).name()));
  }
  return files;
}

cv::Mat readMask(const fs::path& file) {
  const cv::Mat mask = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
  if (mask.empty()) throw Error(fmt::format("{}: cannot read as an image", file.string()));
  return mask;
}

// Camera c's frames k + offsets[c] for every camera, or nothing where one has no mask of it.
bool frameSet(const std::vector<MaskFrames>& masks, const std::vector<int>& offsets, int k,
              std::vector<const LowResSilhouette*>& set) {
  set.resize(masks.size());
  for (size_t c = 0; c < masks.size(); ++c) {
    const auto it = masks[c].find(k + offsets[c]);
    if (it == masks[c].end()) return false;
    set[c] = &it->second;
  }
  return true;
}

// The session frames k (the first camera's footage frame less its offset) every camera has a mask
// of under `offsets`.
std::vector<int> commonFrames(const std::vector<MaskFrames>& masks,
                              const std::vector<int>& offsets) {
  std::vector<int> frames;
  std::vector<const LowResSilhouette*> set;
  for (const auto& [frame, mask] : masks[0])
    if (frameSet(masks, offsets, frame - offsets[0], set)) frames.push_back(frame - offsets[0]);
  return frames;
}

struct Score {
  double mean = 0;    // the share of the masks explained
  double volume = 0;  // the hull's voxels a frame
  std::vector<double> per_camera;
  int frames = 0;
};

// How much of every camera's masks the hull carved from all of them explains under `offsets`:
// the share of each mask's cells within a cell of a kept voxel's, averaged over the frames.
class HullAgreement {
 public:
  HullAgreement(const VisualHullLocator& hull, const std::vector<MaskFrames>& masks)
      : hull_(hull), masks_(masks), covered_(masks.size()) {
    for (size_t c = 0; c < masks.size(); ++c) {
      const LowResSilhouette& any = masks[c].begin()->second;
      covered_[c].assign(size_t(any.width) * any.height, 0);
    }
  }

  // Over the frames every camera has a mask of, or over `only` of them.
  Score score(const std::vector<int>& offsets, const std::vector<int>* only = nullptr) {
    const size_t cameras = masks_.size();
    Score out;
    out.per_camera.assign(cameras, 0.0);
    for (const int k : only ? *only : commonFrames(masks_, offsets)) {
      if (!frameSet(masks_, offsets, k, set_)) continue;
      hull_.carve(set_, kept_);
      out.volume += double(kept_.size());
      for (size_t c = 0; c < cameras; ++c) out.per_camera[c] += explained(int(c), *set_[c]);
      ++out.frames;
    }
    if (out.frames == 0) return out;
    for (double& s : out.per_camera) s /= out.frames;
    out.volume /= out.frames;
    out.mean = std::accumulate(out.per_camera.begin(), out.per_camera.end(), 0.0) / cameras;
    return out;
  }

 private:
  double explained(int c, const LowResSilhouette& mask) {
    std::vector<uint8_t>& covered = covered_[size_t(c)];
    std::fill(covered.begin(), covered.end(), 0);
    const int w = mask.width, h = mask.height;
    for (const uint32_t v : kept_) {
      const int32_t cell = hull_.cell(v, c);
      if (cell < 0) continue;
      const int x = cell % w, y = cell / w;
      for (int dy = std::max(0, y - 1); dy <= std::min(h - 1, y + 1); ++dy)
        for (int dx = std::max(0, x - 1); dx <= std::min(w - 1, x + 1); ++dx)
          covered[size_t(dy) * w + dx] = 1;
    }
    int area = 0, hit = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        if (mask.at(x, y)) {
          ++area;
          hit += covered[size_t(y) * w + x];
        }
    return area > 0 ? double(hit) / area : 0.0;
  }

  const VisualHullLocator& hull_;
  const std::vector<MaskFrames>& masks_;
  std::vector<std::vector<uint8_t>> covered_;
  std::vector<const LowResSilhouette*> set_;
  std::vector<uint32_t> kept_;
};

// The box the actor moves in: the coarse hull's extent over the frames (no offsets), 15 cm more
// each way, within the stage.
StageBox actorBox(const Rig& rig, int step, const std::vector<MaskFrames>& masks,
                  const fs::path& folder) {
  const StageBox stage = stageVolume(rig);
  const VisualHullLocator coarse(rig, step, 0.06, stage);
  std::optional<StageBox> box;
  std::vector<const LowResSilhouette*> set;
  const std::vector<int> none(masks.size(), 0);
  for (const int k : commonFrames(masks, none)) {
    frameSet(masks, none, k, set);
    const ActorLocation where = coarse.locate(set);
    if (!where.found) continue;
    if (!box) box = StageBox{where.lower, where.upper};
    box->lower = box->lower.cwiseMin(where.lower);
    box->upper = box->upper.cwiseMax(where.upper);
  }
  if (!box)
    throw Error(fmt::format(
        "{}: the masks carve nothing in any frame the cameras share: the masks are not of this "
        "rig's cameras, or the rig's calibration is wrong",
        folder.string()));
  const Eigen::Vector3d margin = Eigen::Vector3d::Constant(0.15);
  return StageBox{(box->lower - margin).cwiseMax(stage.lower),
                  (box->upper + margin).cwiseMin(stage.upper)};
}

// The masks, and the rig at their size (cropped as footage import takes it).
struct LoadedMasks {
  Rig rig;
  int step = 4;
  std::vector<MaskFrames> masks;  // the rig's order
  std::vector<std::string> notes;
};

// Every camera's masks as silhouettes of one step, about 240 cells along the longest side,
// decoded on every core.
LoadedMasks loadMasks(const Rig& calibrated, const fs::path& folder,
                      const std::function<void(int, int)>& progress) {
  const int cameras = calibrated.cameraCount();
  const std::vector<std::map<int, fs::path>> files = maskFiles(calibrated, folder);
  LoadedMasks out;
  std::vector<Camera> sized;
  int longest = 0;
  for (int c = 0; c < cameras; ++c) {
    const auto& [frame, file] = *files[size_t(c)].begin();
    const cv::Mat first = readMask(file);
    std::string note;
    sized.push_back(cameraForFootage(calibrated.camera(c), first.cols, first.rows, file, note));
    if (!note.empty()) out.notes.push_back(note);
    longest = std::max({longest, first.cols, first.rows});
  }
  out.rig = Rig(sized, calibrated.nodes());
  out.rig.setStage(calibrated.stage());
  out.step = std::max(4, longest / 240);

  std::vector<std::pair<int, std::pair<int, fs::path>>> jobs;
  for (int c = 0; c < cameras; ++c)
    for (const auto& [frame, file] : files[size_t(c)]) jobs.push_back({c, {frame, file}});
  std::vector<LowResSilhouette> loaded(jobs.size());
  std::mutex lock;
  std::string failure;
  int done = 0;
  cv::parallel_for_(cv::Range(0, int(jobs.size())), [&](const cv::Range& range) {
    for (int j = range.start; j < range.end; ++j) {
      const auto& [c, frame_file] = jobs[size_t(j)];
      const Camera& camera = out.rig.camera(c);
      try {
        const cv::Mat mask = readMask(frame_file.second);
        if (mask.cols != camera.width() || mask.rows != camera.height())
          throw Error(fmt::format("{}: a {}x{} mask, camera '{}''s others are {}x{}",
                                  frame_file.second.string(), mask.cols, mask.rows, camera.name(),
                                  camera.width(), camera.height()));
        const cv::Mat binary = mask > 127;
        maskSilhouette(binary.data, binary.cols, binary.rows, c, out.step, loaded[size_t(j)]);
      } catch (const Error& e) {
        const std::lock_guard<std::mutex> hold(lock);
        if (failure.empty()) failure = e.what();
      }
      const std::lock_guard<std::mutex> hold(lock);
      if (progress) progress(++done, int(jobs.size()));
    }
  });
  if (!failure.empty()) throw Error(failure);
  out.masks.resize(size_t(cameras));
  for (size_t j = 0; j < jobs.size(); ++j)
    out.masks[size_t(jobs[j].first)][jobs[j].second.first] = std::move(loaded[j]);
  return out;
}

// The frames both offset sets give every camera a mask of.
std::vector<int> framesOfBoth(const std::vector<MaskFrames>& masks, const std::vector<int>& a,
                              const std::vector<int>& b) {
  const std::vector<int> fa = commonFrames(masks, a), fb = commonFrames(masks, b);
  std::vector<int> both;
  std::set_intersection(fa.begin(), fa.end(), fb.begin(), fb.end(), std::back_inserter(both));
  return both;
}

// The search: each free camera's offset tried over the range with the others kept (in parallel,
// every trial on the frames all of them share, so that none wins by the frames it leaves out),
// then two cameras moved together a step either way (a pair out of step with the rest together
// is a local optimum of moving one at a time), until neither move helps.
class OffsetSearch {
 public:
  OffsetSearch(const VisualHullLocator& hull, const std::vector<MaskFrames>& masks,
               std::vector<int> offsets, std::vector<bool> fixed, bool anchored, int spacing,
               int range, int enough)
      : hull_(hull),
        masks_(masks),
        offsets_(std::move(offsets)),
        fixed_(std::move(fixed)),
        anchored_(anchored),
        spacing_(spacing),
        enough_(enough),
        records_(masks.size()) {
    const int reach = range / spacing * spacing;
    for (int o = -reach; o <= reach; o += spacing) candidates_.push_back(o);
    // Nearest to none first: on a tie the smaller offset wins.
    std::sort(candidates_.begin(), candidates_.end(), [](int a, int b) {
      return std::abs(a) < std::abs(b) || (std::abs(a) == std::abs(b) && a > b);
    });
  }

  void run(const std::function<void(int, int)>& progress) {
    constexpr int kRounds = 6;
    for (int round = 0; round < kRounds; ++round) {
      bool moved = false;
      for (int c = 0; c < int(masks_.size()); ++c) {
        if (!fixed_[size_t(c)]) moved = moveOne(c) || moved;
        if (progress) progress(round * int(masks_.size()) + c + 1, kRounds * int(masks_.size()));
      }
      if (!moved && !movePairs()) break;
    }
  }
  const std::vector<int>& offsets() const { return offsets_; }
  FootageSyncCamera& record(int c) { return records_[size_t(c)]; }

 private:
  // Scores of `trials`, on every core, over `frames`.
  std::vector<Score> scoreAll(const std::vector<std::vector<int>>& trials,
                              const std::vector<int>& frames) const {
    std::vector<Score> scores(trials.size());
    cv::parallel_for_(cv::Range(0, int(trials.size())), [&](const cv::Range& range) {
      HullAgreement mine(hull_, masks_);
      for (int i = range.start; i < range.end; ++i)
        scores[size_t(i)] = mine.score(trials[size_t(i)], &frames);
    });
    return scores;
  }

  // The frames every trial gives every camera a mask of.
  std::vector<int> framesOfAll(const std::vector<std::vector<int>>& trials) const {
    std::vector<int> shared = commonFrames(masks_, trials[0]);
    for (size_t i = 1; i < trials.size(); ++i) {
      std::vector<int> next;
      const std::vector<int> these = commonFrames(masks_, trials[i]);
      std::set_intersection(shared.begin(), shared.end(), these.begin(), these.end(),
                            std::back_inserter(next));
      shared = std::move(next);
    }
    return shared;
  }

  void normalise(std::vector<int>& offsets) const {
    const int first = anchored_ ? 0 : offsets[0];
    for (int& o : offsets) o -= first;
  }

  bool moveOne(int c) {
    std::vector<std::vector<int>> trials = {offsets_};
    for (const int o : candidates_) {
      trials.push_back(offsets_);
      trials.back()[size_t(c)] = o;
    }
    const std::vector<int> shared = framesOfAll(trials);
    if (int(shared.size()) < enough_) return false;
    const std::vector<Score> scores = scoreAll(trials, shared);
    // The best (trial 0, the offset kept, unless another is better) and the next best offset.
    size_t best = 0;
    for (size_t i = 1; i < scores.size(); ++i)
      if (scores[i].mean > scores[best].mean * (1 + 1e-9)) best = i;
    std::optional<size_t> next;
    for (size_t i = 1; i < scores.size(); ++i)
      if (trials[i][size_t(c)] != trials[best][size_t(c)] &&
          (!next || scores[i].mean > scores[*next].mean))
        next = i;
    const bool moved = trials[best][size_t(c)] != offsets_[size_t(c)];
    offsets_ = trials[best];
    const int first = anchored_ ? 0 : offsets_[0];
    normalise(offsets_);
    FootageSyncCamera& r = records_[size_t(c)];
    r.best_agreement = scores[best].mean;
    r.runner_up = (next ? trials[*next][size_t(c)] : trials[best][size_t(c)]) - first;
    r.runner_up_agreement = next ? scores[*next].mean : scores[best].mean;
    return moved;
  }

  bool movePairs() {
    std::vector<std::vector<int>> trials = {offsets_};
    const int cameras = int(masks_.size());
    for (int a = 0; a < cameras; ++a)
      for (int b = a + 1; b < cameras; ++b)
        for (const int d : {-spacing_, spacing_}) {
          if (fixed_[size_t(a)] || fixed_[size_t(b)]) continue;
          trials.push_back(offsets_);
          trials.back()[size_t(a)] += d;
          trials.back()[size_t(b)] += d;
        }
    const std::vector<int> shared = framesOfAll(trials);
    if (trials.size() < 2 || int(shared.size()) < enough_) return false;
    const std::vector<Score> scores = scoreAll(trials, shared);
    size_t best = 0;
    for (size_t i = 1; i < scores.size(); ++i)
      if (scores[i].mean > scores[best].mean * (1 + 1e-9)) best = i;
    if (best == 0) return false;
    offsets_ = trials[best];
    normalise(offsets_);
    return true;
  }

  const VisualHullLocator& hull_;
  const std::vector<MaskFrames>& masks_;
  std::vector<int> offsets_;
  std::vector<bool> fixed_;
  bool anchored_;
  int spacing_, enough_;
  std::vector<int> candidates_;
  std::vector<FootageSyncCamera> records_;
};

}  // namespace

FootageSync estimateFootageSync(const Rig& calibrated, const fs::path& folder,
                                const FootageSyncOptions& options,
                                const std::function<void(int, int)>& progress) {
  const int cameras = calibrated.cameraCount();
  if (cameras < 2) throw Error("footage sync: needs two cameras or more");
  FootageSync out;
  LoadedMasks loaded = loadMasks(calibrated, folder, progress);
  const Rig& rig = loaded.rig;
  const std::vector<MaskFrames>& masks = loaded.masks;
  out.notes = std::move(loaded.notes);

  // Offsets in steps of the masks' spacing (a mask every second frame: even offsets).
  int spacing = 0;
  for (const MaskFrames& m : masks)
    for (auto it = m.begin(), next = std::next(it); next != m.end(); ++it, ++next)
      spacing = std::gcd(spacing, next->first - it->first);
  out.spacing = std::max(1, spacing);

  std::vector<int> offsets(size_t(cameras), 0);
  std::vector<bool> fixed(size_t(cameras), false);
  for (const auto& [name, offset] : options.fixed) {
    const std::optional<int> c = rig.findCamera(name);
    if (!c) throw Error(fmt::format("footage sync: the rig has no camera '{}'", name));
    offsets[size_t(*c)] = offset;
    fixed[size_t(*c)] = true;
  }
  if (int(commonFrames(masks, offsets).size()) < 3)
    throw Error(fmt::format("{}: fewer than 3 frames every camera has a mask of", folder.string()));

  const StageBox box = actorBox(rig, loaded.step, masks, folder);
  std::optional<VisualHullLocator> hull;
  for (double voxel = options.voxel_m; !hull; voxel *= 1.25) {
    try {
      hull.emplace(rig, loaded.step, voxel, box);
    } catch (const std::invalid_argument&) {
      if (voxel > 0.2) throw;
    }
  }
  // With none given, every camera moves against the others, and the offsets are kept relative to
  // the first camera's (a camera the others all run behind is found so too).
  const int enough = std::max(3, std::min(int(masks[0].size()) / 2, 10));
  OffsetSearch search(*hull, masks, offsets, fixed, !options.fixed.empty(), out.spacing,
                      options.range, enough);
  search.run(progress);
  offsets = search.offsets();

  // The offsets found and none, on the frames both give every camera a mask of.
  HullAgreement agreement(*hull, masks);
  const std::vector<int> none(size_t(cameras), 0), shared = framesOfBoth(masks, offsets, none);
  const Score found = agreement.score(offsets, &shared), unshifted = agreement.score(none, &shared);
  out.agreement = found.mean;
  out.unshifted = unshifted.mean;
  out.frames = int(shared.size());
  for (int c = 0; c < cameras; ++c) {
    FootageSyncCamera& record = out.cameras.emplace_back(search.record(c));
    record.camera = rig.camera(c).name();
    record.offset = offsets[size_t(c)];
    record.fixed = fixed[size_t(c)];
    record.agreement = found.per_camera[size_t(c)];
    record.unshifted = unshifted.per_camera[size_t(c)];
    // Hardly better: the next best leaves less than a quarter more of the masks unexplained.
    if (!record.fixed && 1 - record.best_agreement > 0.8 * (1 - record.runner_up_agreement))
      out.notes.push_back(fmt::format(
          "camera '{}': offset {:+d} agrees hardly better than {:+d} ({:.3f} against {:.3f}): "
          "check it in the footage, or give it (--offset)",
          record.camera, record.offset, record.runner_up, record.best_agreement,
          record.runner_up_agreement));
  }
  return out;
}

std::string describeFootageSync(const FootageSync& sync) {
  std::string text = fmt::format("{:<12} {:>7} {:>10} {:>10}  {}\n", "camera", "offset",
                                 "agreement", "unshifted", "next best offset");
  for (const FootageSyncCamera& c : sync.cameras)
    text += fmt::format("{:<12} {:>+7d} {:>10.3f} {:>10.3f}  {}\n", c.camera, c.offset, c.agreement,
                        c.unshifted,
                        c.fixed ? std::string("(given)")
                                : fmt::format("{:+d} ({:.3f} against {:.3f} over all)", c.runner_up,
                                              c.runner_up_agreement, c.best_agreement));
  text += fmt::format(
      "the hull explains {:.3f} of the masks at these offsets, {:.3f} unshifted ({} frames; "
      "offsets in steps of {})\n",
      sync.agreement, sync.unshifted, sync.frames, sync.spacing);
  return text;
}

}  // namespace lumistage
