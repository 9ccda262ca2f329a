#include "app/cli/eval_command.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <optional>

#include "app/cli/checks.h"
#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/base/output_path.h"
#include "core/body/human_model.h"
#include "core/capture/session_reader.h"
#include "core/capture/session_writer.h"
#include "core/eval/eval_report.h"
#include "core/eval/leave_one_out.h"
#include "core/eval/mocap_eval.h"
#include "core/eval/percentile.h"
#include "core/eval/segmentation_eval.h"
#include "core/eval/surface_metrics.h"
#include "core/eval/view_metrics.h"
#include "core/imaging/clean_plate.h"
#include "core/net/posed_body.h"
#include "core/refine/frame_refiner.h"
#include "core/render/egl_context.h"
#include "core/sim/studio_config.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

// `count` frame indices spread evenly over [0, total), each in the middle of its share, without
// repeats.
std::vector<int> spreadFrames(int total, int count) {
  std::vector<int> frames;
  for (int k = 0; k < count && total > 0; ++k) {
    const int i = int((k + 0.5) * total / count);
    if (frames.empty() || frames.back() != i) frames.push_back(i);
  }
  return frames;
}

// Frames the refinement runs before a scored frame, so that its temporal term holds as in the
// pipeline (4 and 10 score the same on the walk).
constexpr int kWarmFrames = 4;

// Where the refinement's offsets miss the best ones (refined less best, mm, outward positive):
// their 10th, 50th and 90th percentiles, and the shares of vertices more than kOffsetMissMm inside
// and outside their best offset. The scores say how much the geometry costs a view; these say
// which way the refinement errs (docs/lumigraph.md: its misses inside the actor cost the most).
constexpr double kOffsetMissMm = 2.0;
void addOffsetErrors(std::vector<double>& error_mm, EvalReport& report) {
  double inward = 0, outward = 0;
  for (double e : error_mm) {
    inward += e < -kOffsetMissMm;
    outward += e > kOffsetMissMm;
  }
  const double share = error_mm.empty() ? std::nan("") : 100.0 / double(error_mm.size());
  report.set("render", "loo_offset_inward_pct", inward * share);
  report.set("render", "loo_offset_outward_pct", outward * share);
  for (const auto& [key, fraction] : {std::pair{"loo_offset_error_mm_p10", 0.1},
                                      {"loo_offset_error_mm_p50", 0.5},
                                      {"loo_offset_error_mm_p90", 0.9}})
    report.set("render", key, nearestRankPercentile(error_mm, fraction));
}

// The leave-one-out scores of each variant of the mesh (the best offsets' and the true surface's
// only where the session has the truth), overall, per frame and per camera.
struct LeaveOneOutVariants {
  const LeaveOneOutSummary &refined, &unrefined, &strict, &best_offsets, &truth;
};
void reportLeaveOneOut(const SessionReader& session, const std::vector<int>& frames,
                       const LeaveOneOutVariants& v, EvalReport& report) {
  const bool has_truth = session.hasTruth();
  const LeaveOneOutSummary &refined = v.refined, &unrefined = v.unrefined, &strict = v.strict,
                           &best_offsets = v.best_offsets, &truth = v.truth;
  const std::pair<const char*, const ViewScore*> variants[] = {
      {"", &refined.mean},
      {"_unrefined", &unrefined.mean},
      {"_strict", &strict.mean},
      {"_best_offsets", &best_offsets.mean},
      {"_truth_surface", &truth.mean}};
  for (const auto& [suffix, mean] : variants) {
    if (!has_truth && (mean == &best_offsets.mean || mean == &truth.mean)) continue;
    const std::string s = suffix;
    report.set("render", "loo_psnr_db" + s, mean->psnr_db);
    report.set("render", "loo_ssim" + s, mean->ssim);
    report.set("render", "loo_matte_psnr_db" + s, mean->matte_psnr_db);
    report.set("render", "loo_missed_pct" + s, mean->missed_pct);
    report.set("render", "loo_beyond_pct" + s, mean->beyond_pct);
    report.set("render", "loo_missed_error_pct" + s, mean->missed_error_pct);
  }
  for (size_t k = 0; k < frames.size(); ++k) {
    report.setFrame(session.frameId(frames[k]), "loo_psnr_db", refined.per_frame[k].psnr_db);
    report.setFrame(session.frameId(frames[k]), "loo_ssim", refined.per_frame[k].ssim);
  }
  for (size_t c = 0; c < refined.per_camera.size(); ++c) {
    const std::string name = session.rig().camera(int(c)).name();
    report.set("render", "loo_psnr_db_" + name, refined.per_camera[c].psnr_db);
    report.set("render", "loo_ssim_" + name, refined.per_camera[c].ssim);
    report.set("render", "loo_psnr_db_unrefined_" + name, unrefined.per_camera[c].psnr_db);
    report.set("render", "loo_ssim_unrefined_" + name, unrefined.per_camera[c].ssim);
    report.set("render", "loo_psnr_db_strict_" + name, strict.per_camera[c].psnr_db);
    report.set("render", "loo_ssim_strict_" + name, strict.per_camera[c].ssim);
    report.set("render", "loo_missed_pct_" + name, refined.per_camera[c].missed_pct);
    report.set("render", "loo_beyond_pct_" + name, refined.per_camera[c].beyond_pct);
    if (!has_truth) continue;
    report.set("render", "loo_psnr_db_truth_surface_" + name, truth.per_camera[c].psnr_db);
    report.set("render", "loo_ssim_truth_surface_" + name, truth.per_camera[c].ssim);
  }
}

// Section "render": every camera's view rendered from the others with the unstructured
// lumigraph, compared with its image over the truth mask (docs/lumigraph.md), on the pipeline's
// own geometry — the generic human where the tracker sees the actor, refined from the images
// (loo_psnr_db, loo_ssim) — the same refined without the scored camera's image (the strict
// score: nothing of the view it renders went into its geometry; loo_psnr_db_strict), on that mesh
// unrefined, with each vertex at its best offset (what a refinement could reach on the tracked
// mesh), and on the true surface (the upper bound).
// With `pictures` given, every refined view is also written there beside the camera's image and
// their error map (comparisonPicture), as <frame id>_<camera>.png. On a session without truth
// (a real take) the views are scored over the masks it carries, or keyed (ScoreMasks), and the
// variants that need the true surface (best offsets, the true surface) are left out.
void addLeaveOneOut(const SessionReader& session, const CameraPlates& plates,
                    const SkinnedMesh& generic, const MocapEvalResult& tracked,
                    const RefineConfig& refine, int frame_count, const fs::path& pictures,
                    EvalReport& report) {
  const int total = std::min<int>(session.frameCount(), static_cast<int>(tracked.poses.size()));
  // Spread over the tracked frames (a real take may hold the actor in a few of them only).
  std::vector<int> tracked_frames, frames;
  for (int i = 0; i < total && i < static_cast<int>(tracked.valid.size()); ++i)
    if (tracked.valid[i]) tracked_frames.push_back(i);
  for (int k : spreadFrames(int(tracked_frames.size()), frame_count))
    frames.push_back(tracked_frames[k]);
  const bool has_truth = session.hasTruth();
  report.setText("render", "loo_masks", scoreMasksName(scoreMasksOf(session)));
  EglContext gl;
  LumigraphParams fine;  // the true surface is finely tessellated: rendered as it is
  fine.phong_subdivision = false;
  LeaveOneOutSummary truth;
  if (has_truth)
    truth = evaluateLeaveOneOut(
        session, frames, [&](int i, int) { return truthSurface(session, i); },
        LeaveOneOutMeshes::kOnePerFrame, fine, {}, &plates);
  Pose pose;
  std::vector<Eigen::Affine3f> transforms;
  Eigen::Matrix3Xf positions, normals;
  // Each frame's pose message once: the meshes below pose the same frames many times over.
  std::vector<std::optional<PoseData>> messages(tracked.poses.size());
  const auto posed = [&](int i) {
    if (!messages[i])
      messages[i] =
          poseMessageFor(generic.skeleton, tracked.skeleton, tracked.poses[i], tracked.joints[i]);
    posedBodyMesh(generic, *messages[i], pose, transforms, positions, normals);
  };
  const LeaveOneOutSummary unrefined = evaluateLeaveOneOut(
      session, frames,
      [&](int i, int) {
        posed(i);
        TriangleMesh mesh{positions, normals, generic.rest.triangles};
        return mesh;
      },
      LeaveOneOutMeshes::kOnePerFrame, {}, {}, &plates);
  // Every vertex at the offset along its normal nearest the true surface, in the refinement's
  // range, at 0.5 mm steps: the choice a refinement that knew the truth would make (not a bound:
  // where the pose is off, the nearest point may lie on another limb). Each frame's are kept (m
  // along the posed normals) to measure the refinement's against.
  std::map<int, std::vector<float>> best_offset_m;
  LeaveOneOutSummary best_offsets;
  if (has_truth)
    best_offsets = evaluateLeaveOneOut(
        session, frames,
        [&](int i, int) {
          posed(i);
          TriangleMesh mesh;
          mesh.triangles = generic.rest.triangles;
          nearestOffsetsAlongNormals(positions, normals, SurfaceDistance(truthSurface(session, i)),
                                     refine.t_inward_m, refine.t_max_m, 0.0005, mesh.positions);
          std::vector<float>& t = best_offset_m[i];
          t.resize(positions.cols());
          for (Eigen::Index v = 0; v < positions.cols(); ++v)
            t[v] = (mesh.positions.col(v) - positions.col(v)).dot(normals.col(v));
          mesh.computeNormals();
          return mesh;
        },
        LeaveOneOutMeshes::kOnePerFrame, {}, {}, &plates);
  // The refinement's offsets less the best ones (mm, outward positive), every vertex of every
  // scored frame.
  std::vector<double> offset_error_mm;
  // The tracked frames from kWarmFrames before a scored frame to it, read once for all the meshes
  // of that frame (strict asks for one a camera).
  std::vector<int> window;
  std::vector<std::vector<CameraFrame>> window_images;
  int window_for = -1;
  const auto refined_mesh = [&](int i, int left_out) {
    if (window_for != i) {
      window.clear();
      for (int f = std::max(0, i - kWarmFrames); f <= i; ++f)
        if (f == i || tracked.valid[f]) window.push_back(f);
      window_images.resize(window.size());
      for (size_t k = 0; k < window.size(); ++k)
        readFrameWithMasks(session, window[k], window_images[k]);
      window_for = i;
    }
    // As the pipeline refines: frame after frame, each pulled toward the previous one's offsets
    // (the temporal term).
    FrameRefiner refiner(session.rig(), refine, generic.rest.vertexCount(), generic.rest.triangles);
    refiner.setPlates(plates);
    TriangleMesh mesh;
    mesh.triangles = generic.rest.triangles;
    for (size_t k = 0; k < window.size(); ++k) {
      posed(window[k]);
      refiner.refine(window_images[k], positions, normals, mesh.positions, left_out);
    }
    if (left_out < 0 && has_truth) {
      const std::vector<float>& best = best_offset_m.at(i);
      for (size_t v = 0; v < best.size(); ++v)
        offset_error_mm.push_back(
            std::round(1e6 * (refine.levelOffset(refiner.offsets()[v]) - best[v])) / 1000);
    }
    mesh.computeNormals();
    return mesh;
  };
  ComparisonPicture picture;
  const LeaveOneOutViewSink write_picture = [&](int i, int c, std::span<const uint8_t> rendered,
                                                std::span<const uint8_t> image,
                                                std::span<const uint8_t> mask) {
    const Camera& camera = session.rig().camera(c);
    comparisonPicture(rendered, image, mask, camera.width(), camera.height(), picture);
    writePngAtomically(pictures / fmt::format("{:06}_{}.png", session.frameId(i), camera.name()),
                       {PixelFormat::kRgb8, picture.width, picture.height, picture.rgb.data()});
  };
  const LeaveOneOutSummary refined =
      evaluateLeaveOneOut(session, frames, refined_mesh, LeaveOneOutMeshes::kOnePerFrame, {},
                          pictures.empty() ? LeaveOneOutViewSink() : write_picture, &plates);
  // Strict: camera c's view rendered on a mesh refined without camera c's image.
  const LeaveOneOutSummary strict = evaluateLeaveOneOut(
      session, frames, refined_mesh, LeaveOneOutMeshes::kOnePerLeftOutCamera, {}, {}, &plates);
  report.set("render", "loo_frames", double(frames.size()));
  if (has_truth) addOffsetErrors(offset_error_mm, report);
  reportLeaveOneOut(session, frames, {refined, unrefined, strict, best_offsets, truth}, report);
}

struct EvalArgs {
  std::string session, json, config, loo_pictures, fit_pictures;
  BodyChoice body;
  int cameras = 0, frames = 0, loo_frames = 3, fit_every = 1;
  bool quiet = false, mocap_only = false;
};

// A session without the truth (a real take), or motion capture only: motion capture's frames
// tracked and the posed body against every silhouette, and unless asked for motion capture only,
// every camera left out and rendered from the others over the actor's mask. Against truth/ where
// it is.
void evaluateTake(const EvalArgs& args, const SessionReader& session, EvalReport& report) {
  MocapEvalOptions mocap;
  mocap.camera_count = args.cameras;
  mocap.max_frames = args.frames;
  mocap.pictures = args.fit_pictures;
  mocap.picture_every = args.fit_every;
  const SkinnedMesh body = loadBody(args.body);
  // The clean plates, learnt once for every part.
  const CameraPlates plates = sessionPlates(session);
  mocap.plates = &plates;
  const MocapEvalResult tracked = evaluateMocap(session, body, mocap, report);
  if (!args.mocap_only && args.loo_frames > 0) {
    RefineConfig refine;
    if (!args.config.empty()) refine = loadStudioConfig(args.config).refine;
    addLeaveOneOut(session, plates, body, tracked, refine, args.loo_frames, args.loo_pictures,
                   report);
  }
}

// A session with the truth (the virtual studio's): every stage against it, each adding its section
// in pipeline order.
void evaluateAgainstTruth(const EvalArgs& args, const SessionReader& session, EvalReport& report) {
  // A later stage may use an earlier one's result. Segmentation: each camera's keyer, as the nodes
  // learn it, against the truth masks of four frames spread over the session.
  const int last =
      args.frames > 0 ? std::min(args.frames, session.frameCount()) : session.frameCount();
  // The clean plates, learnt once for every part.
  const CameraPlates plates = sessionPlates(session);
  const SegmentationScore key = evaluateSegmentation(session, spreadFrames(last, 4), &plates);
  report.set("segment", "key_frames", key.frames);
  report.set("segment", "key_missed_pct", key.missed_pct);
  report.set("segment", "key_extra_pct", key.extra_pct);
  report.set("segment", "key_threshold", key.threshold);
  report.set("segment", "key_screen_excess_min", key.dimmest_screen);

  MocapEvalOptions mocap;
  if (args.cameras > session.rig().cameraCount())
    throw Error(fmt::format("--cameras {}: the session's rig has {} cameras", args.cameras,
                            session.rig().cameraCount()));
  mocap.camera_count = args.cameras;
  mocap.max_frames = args.frames;
  mocap.pictures = args.fit_pictures;
  mocap.picture_every = args.fit_every;
  mocap.plates = &plates;
  const SkinnedMesh generic = loadBody(args.body);
  report.set("mocap", "body_vertices", double(generic.rest.vertexCount()));
  const MocapEvalResult tracked = evaluateMocap(session, generic, mocap, report);
  SurfaceEvaluationOptions surface;
  surface.plates = &plates;
  if (!args.config.empty()) surface.refine = loadStudioConfig(args.config).refine;
  if (args.loo_frames > 0)
    addLeaveOneOut(session, plates, generic, tracked, surface.refine, args.loo_frames,
                   args.loo_pictures, report);

  // Refinement: the generic human posed by a fit to the true joints, refined from the images,
  // both measured against the true surface.
  surface.max_frames = args.frames;
  const SurfaceEvaluation e = evaluateSurface(args.session, generic, surface);
  report.set("refine", "surface_frames", e.frames);
  report.set("refine", "surface_mm_unrefined", e.unrefined.mean_mm);
  report.set("refine", "surface_mm_unrefined_p95", e.unrefined.p95_mm);
  report.set("refine", "surface_mm_refined", e.refined.mean_mm);
  report.set("refine", "surface_mm_refined_p95", e.refined.p95_mm);
  report.set("refine", "joint_fit_rms_mm", e.joint_fit_rms_mm);
  report.set("refine", "refine_offset_change_mm", e.offset_change_mm);
  report.set("refine", "refine_bytes_per_node_per_frame", e.statistics_bytes_per_node);
  for (size_t i = 0; i < e.refined_per_frame.size(); ++i) {
    const int64_t frame = surface.first_frame + int64_t(i) * surface.frame_step;
    report.setFrame(frame, "surface_mm_unrefined", e.unrefined_per_frame[i].mean_mm);
    report.setFrame(frame, "surface_mm_refined", e.refined_per_frame[i].mean_mm);
  }
}

}  // namespace

void addEvalCommand(CLI::App& app) {
  auto args = std::make_shared<EvalArgs>();
  CLI::App* eval = app.add_subcommand(
      "eval",
      "measure the studio's stages against a session's ground truth (truth/); on a session "
      "without one (a real take), motion capture's frames tracked and silhouettes, and each "
      "camera's view rendered from the others against its image over the actor's mask (the "
      "session's masks, or keyed)");
  eval->add_option("--session", args->session, "session folder (lumistage synth writes one)")
      ->required();
  eval->add_option("--json", args->json, "write the report as JSON (docs/eval-report.md)");
  eval->add_option("--cameras", args->cameras,
                   "use this many of the rig's cameras, evenly spread (default: all)")
      ->check(within(2, 1000));
  eval->add_option("--frames", args->frames, "only the first N frames (default: all)")
      ->check(within(1, 1e9));
  eval->add_option("--config", args->config,
                   "studio config whose `refine:` section sets the refinement (default: built in)");
  eval->add_option("--loo-frames", args->loo_frames,
                   "frames of the leave-one-camera-out rendering score, spread over the session; "
                   "0: none")
      ->capture_default_str();
  eval->add_option("--loo-pictures", args->loo_pictures,
                   "folder to write every scored view into, beside the camera's image and their "
                   "error map (<frame>_<camera>.png)");
  eval->add_option("--fit-pictures", args->fit_pictures,
                   "folder to write a picture of the tracked body over every camera's silhouette "
                   "into (<frame>.png; green: both, blue: silhouette only, red: body only)");
  eval->add_option("--fit-every", args->fit_every, "with --fit-pictures: a picture every N frames")
      ->capture_default_str()
      ->check(within(1, 1e9));
  eval->add_flag("--mocap-only", args->mocap_only,
                 "motion capture's figures only (no segmentation, rendering or refinement)");
  addBodyOption(*eval, args->body);
  eval->add_flag("--quiet", args->quiet, "no report on standard output");
  eval->callback([args] {
    refuseOutputOverInputs("--json", args->json, {{"--session", args->session}});
    requireOutputFolder("--json", args->json);
    refuseOutputOverInputs("--loo-pictures", args->loo_pictures, {{"--session", args->session}});
    refuseOutputOverInputs("--fit-pictures", args->fit_pictures, {{"--session", args->session}});
    if (!args->loo_pictures.empty() && args->loo_frames == 0)
      throw Error("--loo-pictures: --loo-frames 0 scores no view to picture");
    const SessionReader session(args->session);
    for (const auto& [option, folder] : {std::pair{"--loo-pictures", args->loo_pictures},
                                         {"--fit-pictures", args->fit_pictures}}) {
      if (folder.empty()) continue;
      std::error_code ec;
      fs::create_directories(folder, ec);
      if (ec) throw Error(fmt::format("{} {}: cannot create: {}", option, folder, ec.message()));
    }
    EvalReport report;
    report.setText("session", "session", args->session);
    if (!session.hasTruth() || args->mocap_only) {
      evaluateTake(*args, session, report);
    } else {
      evaluateAgainstTruth(*args, session, report);
    }
    if (!args->json.empty()) writeFileAtomically(args->json, report.toJson());
    if (!args->quiet) fmt::print("{}", report.toText());
    if (!session.hasTruth()) {
      const bool rendered = !args->mocap_only && args->loo_frames > 0;
      fmt::print(stderr,
                 "eval: {} has no ground truth (truth/): motion capture's frames and "
                 "silhouettes{}\n",
                 args->session,
                 rendered ? fmt::format(", and every camera's view rendered from the others over "
                                        "its {} masks",
                                        scoreMasksName(scoreMasksOf(session)))
                          : std::string(" only"));
    }
  });
}

}  // namespace lumistage
