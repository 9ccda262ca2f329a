#include "app/cli/session_commands.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <memory>

#include "app/cli/progress.h"
#include "core/base/error.h"
#include "core/capture/footage_import.h"
#include "core/capture/take_merge.h"
#include "core/eval/footage_sync.h"
#include "core/geometry/rig_file.h"
#include "core/geometry/rig_import.h"
#include "core/imaging/mask_repair.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

// "NAME=VALUE" split at its first '='; throws Error naming the option.
std::pair<std::string, std::string> nameValue(const std::string& text, const char* option) {
  const size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size())
    throw Error(fmt::format("{} '{}': expected CAMERA=VALUE", option, text));
  return {text.substr(0, eq), text.substr(eq + 1)};
}

// Camera `name`'s footage in `folder`: NAME.mp4 (.mkv, .avi, .mov, .webm) or a folder NAME/.
fs::path footageIn(const fs::path& folder, const std::string& name) {
  std::error_code ec;
  for (const char* ext : {".mp4", ".mkv", ".avi", ".mov", ".webm", ".MP4", ".MOV"})
    if (fs::is_regular_file(folder / (name + ext), ec)) return folder / (name + ext);
  if (fs::is_directory(folder / name, ec)) return folder / name;
  throw Error(
      fmt::format("--footage {}: no {}.mp4 (.mkv, .avi, .mov, .webm) or {}/ for camera '{}'",
                  folder.string(), name, name, name));
}

// --offset CAMERA=N options by camera; throws Error naming the option.
std::map<std::string, int> parseOffsets(const std::vector<std::string>& texts, const Rig& rig,
                                        const std::string& rig_file) {
  std::map<std::string, int> offsets;
  for (const std::string& text : texts) {
    const auto [name, value] = nameValue(text, "--offset");
    try {
      size_t used = 0;
      offsets[name] = std::stoi(value, &used);
      if (used != value.size()) throw std::invalid_argument(value);
    } catch (const std::exception&) {
      throw Error(fmt::format("--offset '{}': expected a whole number of frames", text));
    }
    if (!rig.findCamera(name))
      throw Error(fmt::format("--offset '{}': {} has no camera '{}'", text, rig_file, name));
  }
  return offsets;
}

// The offsets the masks agree best under (footage_sync.h), printed as a table; `given` fixed.
FootageSync syncFromMasks(const Rig& rig, const std::string& masks,
                          const std::map<std::string, int>& given, int range) {
  FootageSyncOptions options;
  options.fixed = given;
  options.range = range;
  const FootageSync sync = estimateFootageSync(
      rig, masks, options, [](int done, int total) { printProgress("syncing", done, total); });
  for (const std::string& note : sync.notes) fmt::print("{}\n", note);
  fmt::print("{}", describeFootageSync(sync));
  return sync;
}

// The cameras' calibration as given: a rig file, or another tool's calibration read as `rig
// import` reads it (its notes printed).
Rig calibrationRig(const std::string& path) {
  RigImport calibration = importCalibration(path, {});
  for (const std::string& note : calibration.notes) fmt::print("{}: {}\n", path, note);
  return std::move(calibration.rig);
}

// Repairs the session's masks from a clean plate of each camera (mask_repair.h) and prints how.
void repairMasks(const fs::path& session, const MaskRepairOptions& options) {
  const MaskRepairReport report = repairSessionMasks(
      session, options, [](int done, int total) { printProgress("repairing masks", done, total); });
  for (const std::string& note : report.notes) fmt::print("{}\n", note);
  fmt::print("{}", describeMaskRepair(report));
  fmt::print("repaired the masks of {} frames of {} cameras{}: {} (given: {})\n", report.frames,
             report.cameras.size(), report.again ? " again, from the given ones" : "",
             (session / "masks").string(), (session / "masks-given").string());
}

void addImportCommand(CLI::App& session) {
  struct Args {
    std::string rig, footage, out;
    std::vector<std::string> cameras, offsets;
    FootageImportOptions options;
    bool sync = false, repair_masks = false;
    int sync_range = 10;
  };
  auto a = std::make_shared<Args>();
  CLI::App* import = session.add_subcommand(
      "import",
      "Make a session of footage filmed elsewhere: a video file or an image folder per camera of "
      "a rig, with each camera's frame offset");
  import
      ->add_option("--rig", a->rig,
                   "the cameras' calibration: a rig file, or another tool's as `rig import` reads "
                   "it (Qualisys .qca.txt, Pose2Sim/anipose .toml, OpenCV .yaml/.xml, an EasyMocap "
                   "folder)")
      ->required();
  import->add_option("--footage", a->footage,
                     "a folder holding each camera's footage as CAMERA.mp4 (.mkv, .avi, .mov, "
                     ".webm) or CAMERA/ (images)");
  import->add_option("--camera", a->cameras, "CAMERA=PATH: one camera's video or image folder");
  import->add_option("--offset", a->offsets,
                     "CAMERA=N: this camera's footage runs N frames behind the others (its frame "
                     "k + N is taken with their frame k; negative: ahead)");
  import->add_option("--first", a->options.first, "the footage's first frame taken")
      ->capture_default_str()
      ->check(CLI::Range(0, 100000000));
  import->add_option("--frames", a->options.frames, "at most this many frames (default: all)")
      ->check(CLI::Range(1, 100000000));
  import->add_option("--every", a->options.every, "every n-th frame")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000));
  import
      ->add_option("--fps", a->options.fps,
                   "the footage's frame rate (default: the first video's; needed for images)")
      ->check(CLI::Range(0.1, 10000.0));
  import->add_option("--masks", a->options.masks,
                     "another tool's masks of the actor: MASKS/CAMERA/FFFFFF.png (the footage's "
                     "frame numbers, from 0); only frames every camera has one of are taken");
  import->add_flag("--sync", a->sync,
                   "find each camera's offset from the masks' agreement (needs --masks; cameras "
                   "given --offset keep theirs)");
  import->add_option("--sync-range", a->sync_range, "frames searched each way by --sync")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  import->add_flag("--repair-masks", a->repair_masks,
                   "repair the masks from a clean plate of each camera learnt from the take (as "
                   "`session masks`; needs --masks): the given ones kept in masks-given/");
  import->add_option("-o,--out", a->out, "the session's folder (new or empty)")->required();
  import->callback([a] {
    const Rig rig = calibrationRig(a->rig);
  std::map<std::string, int> offsets = parseOffsets(a->offsets, rig, a->rig);
  std::map<std::string, fs::path> paths;
  for (const std::string& text : a->cameras) {
    const auto [name, path] = nameValue(text, "--camera");
    paths[name] = path;
  }
  std::vector<FootageSource> sources;
  for (const Camera& camera : rig.cameras()) {
    const auto given = paths.find(camera.name());
    fs::path path;
    if (given != paths.end()) {
      path = given->second;
      paths.erase(given);
    } else if (!a->footage.empty()) {
      path = footageIn(a->footage, camera.name());
    } else {
      throw Error(fmt::format("camera '{}': no footage (--camera {}=PATH or --footage DIR)",
                              camera.name(), camera.name()));
    }
    sources.push_back(
        {camera.name(), path, offsets.count(camera.name()) ? offsets[camera.name()] : 0});
  }
  if (!paths.empty())
    throw Error(fmt::format("--camera {}=...: {} has no camera '{}'", paths.begin()->first, a->rig,
                            paths.begin()->first));
  if (a->repair_masks && a->options.masks.empty())
    throw Error("--repair-masks: needs the actor's masks (--masks DIR) to repair");
  if (a->sync) {
    if (a->options.masks.empty())
      throw Error("--sync: needs the actor's masks (--masks DIR) to compare the cameras");
    const FootageSync sync = syncFromMasks(rig, a->options.masks.string(), offsets, a->sync_range);
    for (size_t c = 0; c < sources.size(); ++c) sources[c].offset = sync.cameras[c].offset;
  }
  const FootageImportReport report =
      importFootage(rig, sources, a->out, a->options,
                    [](int done, int total) { printProgress("importing", done, total); });
  for (const std::string& note : report.notes) fmt::print("{}\n", note);
  std::string shifts;
  for (const FootageSource& s : sources)
    shifts += fmt::format("{}{} {:+d}", shifts.empty() ? "" : ", ", s.camera, s.offset);
  fmt::print("imported {} frames of {} cameras (offsets: {}) into {}\n", report.frames,
             sources.size(), shifts, a->out);
  if (a->repair_masks) repairMasks(a->out, {});
});
}  // namespace

}  // namespace lumistage

void addSessionCommands(CLI::App& app) {
  CLI::App* session = app.add_subcommand("session", "Work with recorded sessions and takes");
  session->require_subcommand(1);
  addImportCommand(*session);

  struct SyncArgs {
    std::string rig, masks;
    std::vector<std::string> offsets;
    int range = 10;
  };
  auto y = std::make_shared<SyncArgs>();
  CLI::App* sync = session->add_subcommand(
      "sync",
      "Find how many frames each camera's footage runs behind the others, from masks of the "
      "actor (the offsets under which the visual hull explains the most of every mask)");
  sync->add_option("--rig", y->rig, "the cameras' calibration (a rig file, or as session import)")
      ->required();
  sync->add_option("--masks", y->masks, "the masks: MASKS/CAMERA/FFFFFF.png by frame")->required();
  sync->add_option("--offset", y->offsets, "CAMERA=N: a camera whose offset is known");
  sync->add_option("--range", y->range, "frames searched each way")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  sync->callback([y] {
    const Rig rig = calibrationRig(y->rig);
    const FootageSync found =
        syncFromMasks(rig, y->masks, parseOffsets(y->offsets, rig, y->rig), y->range);
    std::string line;
    for (const FootageSyncCamera& c : found.cameras)
      if (c.offset != 0) line += fmt::format(" --offset {}={}", c.camera, c.offset);
    fmt::print("session import options:{}\n", line.empty() ? " (none: in step)" : line);
  });

  struct MasksArgs {
    std::string session;
    MaskRepairOptions options;
  };
  auto k = std::make_shared<MasksArgs>();
  CLI::App* masks = session->add_subcommand(
      "masks",
      "Repair a session's masks (another tool's: a limb missed, furniture taken in) from a clean "
      "plate of each camera learnt from the take itself: each frame keyed against it where it is "
      "known; the given masks kept in masks-given/, the repaired ones in masks/");
  masks->add_option("--session", k->session, "the session's folder (with masks/)")->required();
  masks->add_option("--pictures", k->options.pictures,
                    "write pictures of the repairs here to look at (CAMERA-FFFFFF.png: green both "
                    "masks, red the repair's only, blue the given one's only, purple stripes where "
                    "the plate is unknown)");
  masks
      ->add_option("--picture-every", k->options.picture_every, "with --pictures: every N-th frame")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  masks->callback([k] { repairMasks(k->session, k->options); });

  struct MergeArgs {
    std::vector<std::string> parts;
    std::string out, rig, image_files;
  };
  auto m = std::make_shared<MergeArgs>();
  CLI::App* merge = session->add_subcommand(
      "merge",
      "Join a take's parts (each node records its own cameras: TAKES/<take>/<node>/) into one "
      "session of every camera: the frames all parts hold");
  merge->add_option("parts", m->parts, "the take's folder, or its parts' folders")->required();
  merge->add_option("--out", m->out, "the merged session's folder (new or empty)")->required();
  merge->add_option("--rig", m->rig,
                    "order cameras and nodes as in this rig file (default: part after part)");
  merge
      ->add_option("--image-files", m->image_files,
                   "store the images as png (a third smaller: encoded again, 10 ms or more an "
                   "image) or pnm (default: as the parts, copied)")
      ->check(CLI::IsMember({"pnm", "png"}));
  merge->callback([m] {
    std::vector<std::filesystem::path> paths(m->parts.begin(), m->parts.end());
    const std::vector<std::filesystem::path> parts = takeParts(paths);
    std::optional<Rig> rig;
    if (!m->rig.empty()) rig = loadRig(m->rig);
    std::optional<ImageFiles> files;
    if (!m->image_files.empty()) files = parseImageFiles(m->image_files);
    const TakeMergeReport report = mergeTake(parts, m->out, rig, files, [](int done, int total) {
      printProgress("merging", done, total);
    });
    for (const std::string& note : report.notes) fmt::print("{}\n", note);
    fmt::print("merged {} parts: {} frame sets, {:.1f} MB, into {}\n", parts.size(), report.frames,
               report.bytes / 1e6, m->out);
  });
}

}  // namespace lumistage
