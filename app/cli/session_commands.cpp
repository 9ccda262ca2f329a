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
#include "core/geometry/rig_file.h"

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

void addImportCommand(CLI::App& session) {
  struct Args {
    std::string rig, footage, out;
    std::vector<std::string> cameras, offsets;
    FootageImportOptions options;
  };
  auto a = std::make_shared<Args>();
  CLI::App* import = session.add_subcommand(
      "import",
      "Make a session of footage filmed elsewhere: a video file or an image folder per camera of "
      "a rig, with each camera's frame offset");
  import->add_option("--rig", a->rig, "the cameras' calibration (rig file; `rig import` makes one)")
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
  import->add_option("-o,--out", a->out, "the session's folder (new or empty)")->required();
  import->callback([a] {
    const Rig rig = loadRig(a->rig);
  std::map<std::string, int> offsets;
  for (const std::string& text : a->offsets) {
    const auto [name, value] = nameValue(text, "--offset");
    try {
      size_t used = 0;
      offsets[name] = std::stoi(value, &used);
      if (used != value.size()) throw std::invalid_argument(value);
    } catch (const std::exception&) {
      throw Error(fmt::format("--offset '{}': expected a whole number of frames", text));
    }
    if (!rig.findCamera(name))
      throw Error(fmt::format("--offset '{}': {} has no camera '{}'", text, a->rig, name));
  }
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
  const FootageImportReport report =
      importFootage(rig, sources, a->out, a->options,
                    [](int done, int total) { printProgress("importing", done, total); });
  for (const std::string& note : report.notes) fmt::print("{}\n", note);
  std::string shifts;
  for (const FootageSource& s : sources)
    shifts += fmt::format("{}{} {:+d}", shifts.empty() ? "" : ", ", s.camera, s.offset);
  fmt::print("imported {} frames of {} cameras (offsets: {}) into {}\n", report.frames,
             sources.size(), shifts, a->out);
});
}  // namespace

}  // namespace lumistage

void addSessionCommands(CLI::App& app) {
  CLI::App* session = app.add_subcommand("session", "Work with recorded sessions and takes");
  session->require_subcommand(1);
  addImportCommand(*session);

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
