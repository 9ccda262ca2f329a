#include "app/cli/calibrate_commands.h"

#include <fmt/format.h>

#include <charconv>
#include <filesystem>
#include <map>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "app/cli/checks.h"
#include "app/cli/progress.h"
#include "core/base/error.h"
#include "core/base/output_path.h"
#include "core/calib/board_calibration.h"
#include "core/calib/multicamselfcal_files.h"
#include "core/calib/similarity.h"
#include "core/calib/wand_calibration.h"
#include "core/calib/wand_detector.h"
#include "core/calib/wand_simulation.h"
#include "core/capture/session_reader.h"
#include "core/capture/session_writer.h"
#include "core/geometry/rig_file.h"
#include "core/geometry/ring_rig.h"

namespace lumistage {

namespace fs = std::filesystem;

namespace {

Rig rigOrReference(const std::string& path) {
  return path.empty() ? makeRingRig(RingRigSpec{}) : loadRig(path);
}

void printTruthComparison(const Rig& estimate, const std::string& truth_path) {
  const RigComparison cmp = compareRigs(estimate, loadRig(truth_path));
  fmt::print("against {} (after a similarity alignment of the centres, scale {:.5f}):\n",
             truth_path, cmp.alignment.scale);
  fmt::print(
      "  camera centres: max {:.2f} mm, rms {:.2f} mm; rotations: max {:.4f} deg; focal "
      "lengths: max {:.3f}%; intrinsics: max {:.2f} px\n",
      1e3 * cmp.max_centre_m, 1e3 * cmp.rms_centre_m, cmp.max_rotation_deg, 100 * cmp.max_focal_rel,
      cmp.max_intrinsics_px);
}

// The wand's point in every frame of a recorded session (docs/session-format.md), by the detector.
WandSession detectWandSession(const fs::path& folder, const WandDetectorOptions& detector_options) {
  const SessionReader reader(folder);
  const Rig& rig = reader.rig();
  std::vector<WandCamera> cameras;
  for (const Camera& c : rig.cameras()) cameras.push_back({c.name(), c.width(), c.height()});
  WandSession session(cameras, reader.frameCount());
  WandDetector detector(detector_options);
  std::vector<CameraFrame> frames;
  std::map<std::string, int> rejected;
  for (int i = 0; i < reader.frameCount(); ++i) {
    reader.readFrame(i, frames);
    for (const CameraFrame& f : frames) {
      const WandDetection d = detector.detect(f.image.view());
      if (d.status == WandDetection::Status::kFound) {
        if (rig.camera(f.camera).inImage(d.pixel)) session.set(i, f.camera, d.pixel);
      } else if (d.status != WandDetection::Status::kNone) {
        ++rejected[rig.camera(f.camera).name()];
      }
    }
    printProgress("detect", i + 1, reader.frameCount());
  }
  for (const auto& [camera, count] : rejected) {
    fmt::print(stderr, "note: camera {}: {} frames rejected (several bright blobs or too bright)\n",
               camera, count);
  }
  return session;
}

// Board images: FOLDER/<camera>/<frame number>.png (any image OpenCV reads), the camera names as
// in the rig given for the names and sizes.
BoardSession detectBoardSession(const fs::path& folder, const BoardSpec& board) {
  BoardSession session;
  session.board = board;
  std::vector<fs::path> dirs;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.is_directory()) dirs.push_back(entry.path());
  }
  std::sort(dirs.begin(), dirs.end());
  if (dirs.empty())
    throw Error(folder.string() + ": expected one folder of board images per camera");
  for (const fs::path& dir : dirs) {
    const int camera = static_cast<int>(session.camera_names.size());
    session.camera_names.push_back(dir.filename().string());
    session.image_sizes.emplace_back(0, 0);
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(dir)) files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    for (const fs::path& file : files) {
      const std::string stem = file.stem().string();
      int frame = 0;
      const auto r = std::from_chars(stem.data(), stem.data() + stem.size(), frame);
      if (r.ec != std::errc() || r.ptr != stem.data() + stem.size()) continue;
      const cv::Mat gray = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
      if (gray.empty()) throw Error(file.string() + ": not an image OpenCV can read");
      Eigen::Vector2i& size = session.image_sizes[camera];
      if (size == Eigen::Vector2i(0, 0)) size = {gray.cols, gray.rows};
      if (size != Eigen::Vector2i(gray.cols, gray.rows))
        throw Error(fmt::format("{}: {}x{}, but the camera's other images are {}x{}", file.string(),
                                gray.cols, gray.rows, size.x(), size.y()));
      const cv::Mat packed = gray.isContinuous() ? gray : gray.clone();
      const ImageView view{PixelFormat::kMono8, packed.cols, packed.rows, packed.data};
      if (auto corners = detectBoard(view, board))
        session.views.push_back({frame, camera, std::move(*corners)});
    }
    fmt::print(stderr, "camera {}: board found in {} of {} images\n", session.camera_names.back(),
               std::count_if(session.views.begin(), session.views.end(),
                             [&](const BoardView& v) { return v.camera == camera; }),
               files.size());
  }
  return session;
}

// Above this reprojection RMS a solve has gone wrong (a good rig fits to well under a pixel): the
// rig file it would replace is kept.
constexpr double kDefaultMaxRmsPx = 3.0;

// The report first (where it cannot be written, the rig file is not touched either; by default
// beside the rig, where the studio's calibration check finds it), then the rig unless the solve's
// reprojection RMS is above max_rms_px.
void writeOutputs(const Rig& rig, const CalibrationReport& report, const std::string& out,
                  const std::string& report_path, const std::string& truth, double max_rms_px) {
  fmt::print("{}", summarizeCalibrationReport(report));
  const std::string report_file =
      report_path.empty() ? calibrationReportPathFor(out).string() : report_path;
  saveCalibrationReport(report, report_file);
  fmt::print("wrote {}\n", report_file);
  if (!truth.empty()) printTruthComparison(rig, truth);
  if (!(report.rms_px <= max_rms_px))
    throw Error(fmt::format(
        "reprojection RMS {:.2f} px is above --max-rms {:.2f} px: the solve failed, {} was not "
        "written (see {})",
        report.rms_px, max_rms_px, out, report_file));
  saveRig(rig, out);
  fmt::print("wrote {} ({} cameras on {} nodes)\n", out, rig.cameraCount(), rig.nodeCount());
}

void addMaxRmsOption(CLI::App* command, double& max_rms_px) {
  command
      ->add_option("--max-rms", max_rms_px,
                   "largest reprojection RMS, pixels, at which the rig file is written (a failed "
                   "solve leaves the old one)")
      ->check(within(0.01, 1000))
      ->capture_default_str();
}

struct WandArgs {
  std::string points, session, out, report, initial_rig, truth, save_points;
  double wand_length_m = 0, hfov_deg = 60, max_rms_px = kDefaultMaxRmsPx;
  int cameras_per_node = 3, threshold = 160;
  std::string principal_point = "auto";
};

void runWand(const WandArgs& w) {
  if (w.points.empty() && w.session.empty()) throw Error("give --points FILE or --session DIR");
  // The rig may replace --initial-rig (a recalibration); it must not replace what it is solved
  // from.
  for (const auto& [option, path] : {std::pair<const char*, const std::string&>{"--out", w.out},
                                     {"--report", w.report},
                                     {"--save-points", w.save_points}})
    refuseOutputOverInputs(option, path, {{"--points", w.points}, {"--session", w.session}});
  WandSession data;
  if (!w.points.empty()) {
    data = loadWandSession(w.points);
  } else {
    WandDetectorOptions detector;
    detector.threshold = w.threshold;
    data = detectWandSession(w.session, detector);
    if (!w.save_points.empty()) {
      saveWandSession(data, w.save_points);
      fmt::print("wrote {}\n", w.save_points);
    }
  }
  WandCalibrationOptions options;
  if (!w.initial_rig.empty()) options.initial_rig = loadRig(w.initial_rig);
  options.nominal_hfov_deg = w.hfov_deg;
  options.cameras_per_node = w.cameras_per_node;
  options.wand_length_m = w.wand_length_m;
  using PrincipalPoint = WandCalibrationOptions::PrincipalPoint;
  options.principal_point = w.principal_point == "fixed"    ? PrincipalPoint::kFixed
                            : w.principal_point == "refine" ? PrincipalPoint::kRefined
                                                            : PrincipalPoint::kAuto;
  options.progress = [](const std::string& stage, int done, int total) {
    printProgress(stage.c_str(), done, total);
  };
  fmt::print(stderr, "{} cameras, {} samples\n", data.cameraCount(), data.sampleCount());
  const WandCalibrationResult result = calibrateWand(data, options);
  writeOutputs(result.rig, result.report, w.out, w.report, w.truth, w.max_rms_px);
}

void addWandCommand(CLI::App* calibrate) {
  auto w = std::make_shared<WandArgs>();
  CLI::App* wand = calibrate->add_subcommand(
      "wand",
      "Self-calibrate the rig from a wand session (a bright point waved through the stage)");
  auto* points = wand->add_option("--points", w->points, "wand points file (docs/calibration.md)");
  auto* session = wand->add_option("--session", w->session,
                                   "recorded session of the dark stage and the wand (the detector "
                                   "finds the point in every image)");
  points->excludes(session);
  wand->add_option("--save-points", w->save_points,
                   "with --session: also write the detected points file (add pair and floor lines "
                   "to it for the scale and the floor, then solve it with --points)");
  wand->add_option("-o,--out", w->out, "rig file to write")->required();
  wand->add_option("--report", w->report,
                   "calibration report to write (YAML; default: beside the rig, "
                   "RIG.calibration.yaml, where the studio finds it)");
  wand->add_option("--wand-length", w->wand_length_m,
                   "metres between the wand's two LEDs (the session's pair lines): the scale")
      ->check(within(0.01, 10));
  wand->add_option("--initial-rig", w->initial_rig,
                   "rig file whose intrinsics start the solve (and whose nodes are kept)");
  wand->add_option("--hfov", w->hfov_deg,
                   "horizontal field of view to start from without "
                   "--initial-rig, degrees")
      ->check(CLI::Range(1.0, 179.0))
      ->capture_default_str();
  wand->add_option("--cameras-per-node", w->cameras_per_node)
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  addMaxRmsOption(wand, w->max_rms_px);
  wand->add_option("--threshold", w->threshold,
                   "detector: intensity above which a pixel is the wand")
      ->check(within(1, 254))
      ->capture_default_str();
  wand->add_option("--principal-point", w->principal_point,
                   "the principal points: held where they start (image centre or --initial-rig: "
                   "fixed), refined (refine: weakly determined, needs thousands of samples), or "
                   "refined where that fits the samples 3% better or more (auto; the report says "
                   "which)")
      ->check(CLI::IsMember({"auto", "fixed", "refine"}))
      ->capture_default_str();
  // The older spelling of --principal-point refine.
  wand->add_flag_callback(
          "--refine-principal-point", [w] { w->principal_point = "refine"; },
          "the same as --principal-point refine")
      ->excludes("--principal-point");
  wand->add_option("--truth", w->truth, "rig file of the truth (simulations): print the errors");
  wand->callback([w] { runWand(*w); });
}

struct SynthWandArgs {
  std::string rig, out, multicamselfcal, session;
  WandSimulationOptions sim;
};

// The simulated wand filmed through the rig: a recorded session of the dark stage, a frame a
// sample.
void filmWandSession(const Rig& rig, const SimulatedWandSession& sim, const std::string& folder) {
  SessionWriter writer(folder, rig, PixelFormat::kMono8, 30.0, "lumistage calibrate synth-wand");
  std::vector<Image> images(rig.cameraCount());
  std::vector<ImageView> views(rig.cameraCount());
  const int frames = static_cast<int>(sim.points_m.size());
  for (int f = 0; f < frames; ++f) {
    for (int c = 0; c < rig.cameraCount(); ++c) {
      std::vector<Eigen::Vector2d> spots;
      const std::optional<Eigen::Vector2d> p = rig.camera(c).project(sim.points_m[f]);
      if (p && rig.camera(c).inImage(*p)) spots.push_back(*p);
      renderWandFrame(rig.camera(c), spots, images[c]);
      views[c] = images[c].view();
    }
    writer.writeFrame(f, static_cast<int64_t>(f) * 33'333'333, views);
    printProgress("film", f + 1, frames);
  }
  fmt::print("wrote the session {} ({} frames)\n", folder, frames);
}

void runSynthWand(const SynthWandArgs& sw) {
  const Rig rig = rigOrReference(sw.rig);
  const SimulatedWandSession sim = simulateWandSession(rig, sw.sim);
  saveWandSession(sim.session, sw.out);
  int observations = 0;
  for (int c = 0; c < sim.session.cameraCount(); ++c)
    observations += sim.session.observationCount(c);
  fmt::print("wrote {}: {} samples, {} observations by {} cameras\n", sw.out,
             sim.session.sampleCount(), observations, sim.session.cameraCount());
  if (!sw.session.empty()) filmWandSession(rig, sim, sw.session);
  if (!sw.multicamselfcal.empty()) {
    writeMultiCamSelfCalInput(sim.session, sw.multicamselfcal);
    fmt::print("wrote MultiCamSelfCal input to {}\n", sw.multicamselfcal);
  }
}

void addSynthWandCommand(CLI::App* calibrate) {
  auto sw = std::make_shared<SynthWandArgs>();
  CLI::App* synth_wand = calibrate->add_subcommand(
      "synth-wand", "Simulate a wand session through a known rig (the truth) and write its points");
  synth_wand->add_option("--rig", sw->rig, "the true rig (default: the reference ring rig)");
  synth_wand->add_option("--samples", sw->sim.samples)
      ->check(within(10, 1e6))
      ->capture_default_str();
  synth_wand->add_option("--noise-px", sw->sim.noise_px)
      ->check(within(0, 20))
      ->capture_default_str();
  synth_wand->add_option("--outliers", sw->sim.outlier_fraction, "fraction of observations")
      ->check(within(0, 0.5))
      ->capture_default_str();
  synth_wand->add_option("--dropout", sw->sim.dropout)
      ->check(within(0, 0.9))
      ->capture_default_str();
  synth_wand
      ->add_option("--wand-length", sw->sim.wand_length_m,
                   "> 0: a two-LED wand of this length (pairs of samples)")
      ->check(within(0, 10));
  synth_wand->add_option("--seed", sw->sim.seed)->capture_default_str();
  synth_wand->add_option("-o,--out", sw->out, "wand points file to write")->required();
  synth_wand->add_option("--session", sw->session,
                         "also film it: a recorded session (docs/session-format.md) of the dark "
                         "stage with the wand's LED, a frame a sample, for `calibrate wand "
                         "--session`");
  synth_wand->add_option(
      "--multicamselfcal", sw->multicamselfcal,
      "also write MultiCamSelfCal's input (points.dat, IdMat.dat, Res.dat) here");
  synth_wand->callback([sw] { runSynthWand(*sw); });
}

struct BoardArgs {
  std::string images, out, report, truth, synth_rig;
  BoardSpec board;
  int floor_frame = -1, cameras_per_node = 3, synth_frames = 0;
  double max_rms_px = kDefaultMaxRmsPx;
  uint32_t seed = 1;
};

void runBoard(const BoardArgs& b) {
  b.board.check();
  refuseOutputOverInputs("--out", b.out, {{"--images", b.images}});
  refuseOutputOverInputs("--report", b.report, {{"--images", b.images}});
  BoardSession data;
  if (b.synth_frames > 0) {
    const Rig rig = rigOrReference(b.synth_rig);
    data = simulateBoardSession(rig, b.board, b.synth_frames, b.seed).session;
    fmt::print(stderr, "simulated {} frames: {} board views\n", b.synth_frames, data.views.size());
  } else if (!b.images.empty()) {
    data = detectBoardSession(b.images, b.board);
  } else {
    throw Error("give --images DIR or --synth-frames N");
  }
  BoardCalibrationOptions options;
  options.floor_frame = b.floor_frame;
  options.cameras_per_node = b.cameras_per_node;
  const BoardCalibrationResult result = calibrateBoards(data, options);
  writeOutputs(result.rig, result.report, b.out, b.report, b.truth, b.max_rms_px);
}

void addBoardCommand(CLI::App* calibrate) {
  auto b = std::make_shared<BoardArgs>();
  CLI::App* board = calibrate->add_subcommand(
      "board", "Calibrate the rig from checkerboard views (intrinsics, then joint extrinsics)");
  auto* images = board->add_option("--images", b->images,
                                   "folder with a folder of images per camera, NNN.png per frame");
  auto* synth = board->add_option("--synth-frames", b->synth_frames,
                                  "simulate this many board frames instead (virtual studio)");
  images->excludes(synth);
  board->add_option("--synth-rig", b->synth_rig,
                    "the true rig of --synth-frames (default: reference)");
  board->add_option("--seed", b->seed)->capture_default_str();
  board->add_option("--cols", b->board.cols, "inner corners along a row")->capture_default_str();
  board->add_option("--rows", b->board.rows, "inner corners down a column")->capture_default_str();
  board->add_option("--square", b->board.square_m, "square size, metres")->capture_default_str();
  board->add_option("--floor-frame", b->floor_frame,
                    "frame whose board lies on the floor and defines the world");
  board->add_option("--cameras-per-node", b->cameras_per_node)
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  addMaxRmsOption(board, b->max_rms_px);
  board->add_option("-o,--out", b->out, "rig file to write")->required();
  board->add_option("--report", b->report,
                    "calibration report to write (YAML; default: beside the rig, "
                    "RIG.calibration.yaml, where the studio finds it)");
  board->add_option("--truth", b->truth, "rig file of the truth: print the errors");
  board->callback([b] { runBoard(*b); });
}

}  // namespace

void addCalibrateCommands(CLI::App& app) {
  CLI::App* calibrate = app.add_subcommand(
      "calibrate", "Calibrate the rig: wand self-calibration, checkerboards, simulated sessions");
  calibrate->require_subcommand(1);
  addWandCommand(calibrate);
  addSynthWandCommand(calibrate);
  addBoardCommand(calibrate);
}

}  // namespace lumistage
