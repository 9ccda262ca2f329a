#include "core/eval/mocap_eval.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <ctime>

#include "core/base/error.h"
#include "core/body/human_model.h"
#include "core/body/human_skeleton.h"
#include "core/eval/fit_picture.h"
#include "core/eval/percentile.h"
#include "core/imaging/cell_colours.h"
#include "core/imaging/clean_plate.h"
#include "core/imaging/keyer.h"
#include "core/imaging/silhouettes.h"
#include "core/net/posed_body.h"
#include "core/tracking/mesh_silhouette.h"

namespace lumistage {

namespace {

// CPU time of the calling thread: the fit's cost on one core, whatever else the machine runs.
double threadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec / 1e6;
}

// The truth's joints by the skeleton's joint order (same names).
std::vector<int> truthJointIndex(const SessionReader& session, const Skeleton& skeleton,
                                 const std::vector<std::string>& names) {
  std::vector<int> index;
  for (int j = 0; j < skeleton.jointCount(); ++j) {
    const auto it = std::find(names.begin(), names.end(), skeleton.joint(j).name);
    if (it == names.end())
      throw Error(session.folder().string() + "/truth/joints.csv: no joint '" +
                  skeleton.joint(j).name + "'");
    index.push_back(int(it - names.begin()));
  }
  return index;
}

double silhouetteIou(const LowResSilhouette& a, const LowResSilhouette& b) {
  int both = 0, either = 0;
  for (size_t k = 0; k < a.bits.size(); ++k) {
    both += std::popcount(unsigned(a.bits[k] & b.bits[k]));
    either += std::popcount(unsigned(a.bits[k] | b.bits[k]));
  }
  return either > 0 ? double(both) / either : 0.0;
}

double meanOf(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? std::nan("") : s / v.size();
}

double maxOf(const std::vector<double>& v) {
  return v.empty() ? std::nan("") : *std::max_element(v.begin(), v.end());
}

// What the frames add up to.
struct MocapTally {
  std::vector<double> errors_mm, times_ms, search_ms, wall_times_ms;
  // Per joint over the frames that errors_mm counts: the error's length and its height (tracked
  // less true z), summed, metres.
  std::vector<double> joint_error_m, joint_height_m;
  // The posed body's silhouette against each camera's, summed over the tracked frames.
  std::vector<double> iou_sum;
  int tracked = 0;
};

// The session's figures into the report's "mocap" section.
void reportTally(const MocapTally& t, const Rig& rig, const std::vector<int>& cameras,
                 const PoseTracker& tracker, bool has_truth, int frames, EvalReport& report) {
  const std::string section = "mocap";
  report.set(section, "frames", frames);
  report.set(section, "frames_tracked", t.tracked);
  report.set(section, "cameras", int(cameras.size()));
  if (has_truth) {
    report.set(section, "mpjpe_mm", meanOf(t.errors_mm));
    report.set(section, "mpjpe_mm_max", maxOf(t.errors_mm));
    // The nearest-rank percentile, as the surface's.
    std::vector<double> errors_mm = t.errors_mm;  // nearestRankPercentile orders it
    report.set(section, "mpjpe_mm_p95", nearestRankPercentile(errors_mm, 0.95));
    // Each joint's share: where the error is a bias (the shape calibration's, docs/eval-report.md)
    // the height shows it, whichever way the actor faces.
    // mm a frame counted; NaN when none was.
    const double per_frame = t.errors_mm.empty() ? std::nan("") : 1e3 / double(t.errors_mm.size());
    for (size_t j = 0; j < t.joint_error_m.size(); ++j) {
      const std::string& name = tracker.skeleton().joint(int(j)).name;
      report.set(section, "joint_error_mm_" + name, t.joint_error_m[j] * per_frame);
      report.set(section, "joint_height_error_mm_" + name, t.joint_height_m[j] * per_frame);
    }
  }
  double iou = 0;
  for (int c : cameras) {
    const double camera_iou = t.tracked > 0 ? t.iou_sum[size_t(c)] / t.tracked : std::nan("");
    report.set(section, "silhouette_iou_" + rig.camera(c).name(), camera_iou);
    iou += camera_iou / double(cameras.size());
  }
  report.set(section, "silhouette_iou", iou);
  report.set(section, "pose_ms", meanOf(t.times_ms));
  report.set(section, "pose_ms_max", maxOf(t.times_ms));
  report.set(section, "pose_wall_ms", meanOf(t.wall_times_ms));
  report.set(section, "init_ms", maxOf(t.search_ms));
  // The calibrated height; the default shape is no measure when nobody was tracked.
  report.set(section, "actor_height_m", t.tracked > 0 ? tracker.shape().height_m : std::nan(""));
  // How tall it stands (statureOf), which the truth's is measured against.
  report.set(section, "actor_stature_m", t.tracked > 0 ? statureOf(tracker.shape()) : std::nan(""));
}

}  // namespace

MocapEvalResult evaluateMocap(const SessionReader& session, const SkinnedMesh& generic,
                              const MocapEvalOptions& options, EvalReport& report) {
  const Rig& rig = session.rig();
  const int all = rig.cameraCount();
  const int count = options.camera_count > 0 ? std::min(options.camera_count, all) : all;
  std::vector<int> cameras;
  for (int k = 0; k < count; ++k) cameras.push_back(k * all / count);
  PoseTrackerOptions tracker_options = options.tracker;
  tracker_options.silhouette_step = options.silhouette_step;
  PoseTracker tracker(rig, trackingModelFor(generic), tracker_options);

  std::vector<std::vector<Eigen::Vector3d>> truth;
  std::vector<std::string> names;
  if (session.hasTruth()) truth = session.readTruthJoints(&names);
  std::vector<int> truth_index;
  if (!truth.empty()) truth_index = truthJointIndex(session, tracker.skeleton(), names);

  const int frames = options.max_frames > 0 ? std::min(options.max_frames, session.frameCount())
                                            : session.frameCount();
  MocapEvalResult result;
  std::vector<CameraFrame> images;
  std::vector<LowResSilhouette> silhouettes(all);
  std::vector<const LowResSilhouette*> pointers;
  // The actor's colours, as a node samples them with its silhouettes.
  std::vector<CellColours> colours(all);
  std::vector<const CellColours*> colour_pointers;
  const GreenScreenKeyer keyer;
  // A stage without a green screen is keyed on its clean plate, as the nodes key it.
  const CameraPlates plates = platesOf(session, options.plates);
  MocapTally t;
  t.joint_error_m.assign(truth_index.size(), 0.0);
  t.joint_height_m.assign(truth_index.size(), 0.0);
  t.iou_sum.assign(size_t(all), 0.0);
  bool initialised = false;
  // The session's own masks (another tool's) stand for the key where it has them.
  const bool masks = session.hasMasks();
  std::vector<LowResSilhouette> bodies(cameras.size());
  std::vector<ImageView> views;
  Pose body_pose;
  std::vector<Eigen::Affine3f> transforms;
  Eigen::Matrix3Xf positions, normals;
  for (int f = 0; f < frames; ++f) {
    const bool picture = !options.pictures.empty() && f % options.picture_every == 0;
    // The actor's colours on the frames a node sends them (kColourEveryFrames), read only when the
    // tracker would use them (its arms not yet placed by them).
    const bool coloured = f % kColourEveryFrames == 0 && tracker.wantsColours();
    if (!masks || picture || coloured) session.readFrame(f, images, cameras);
    pointers.clear();
    colour_pointers.clear();
    for (int c : cameras) {
      if (masks) {
        const std::vector<uint8_t> mask = session.readMask(c, f);
        maskSilhouette(mask.data(), rig.camera(c).width(), rig.camera(c).height(), c,
                       options.silhouette_step, silhouettes[c]);
      } else if (plates[c]) {
        computeSilhouette(*plates[c], images[c].image.view(), c, options.silhouette_step,
                          silhouettes[c]);
      } else {
        computeSilhouette(keyer, images[c].image.view(), c, options.silhouette_step,
                          silhouettes[c]);
      }
      pointers.push_back(&silhouettes[c]);
      if (coloured) {
        sampleCellColours(images[c].image.view(), silhouettes[c], colours[c]);
        colour_pointers.push_back(&colours[c]);
      }
    }
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = threadCpuMs();
    const TrackResult& r = tracker.track(pointers, colour_pointers);
    const double ms = threadCpuMs() - cpu_start;
    const double wall_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    // Frames that initialise (or search for the actor) are timed apart from tracked frames.
    (r.state == TrackState::kTracking || r.state == TrackState::kLost ? t.times_ms : t.search_ms)
        .push_back(ms);
    t.wall_times_ms.push_back(wall_ms);
    report.setFrame(f, "pose_ms", ms);
    report.setFrame(f, "tracked", r.valid() ? 1 : 0);
    result.valid.push_back(r.valid());
    result.poses.push_back(r.pose);
    result.joints.push_back(r.valid() ? r.joints : std::vector<Eigen::Vector3d>{});
    for (LowResSilhouette& b : bodies) b.bits.clear();
    auto writePicture = [&] {
      if (!picture) return;
      views.clear();
      for (int c : cameras) views.push_back(images[size_t(c)].image.view());
      writeFitPicture(options.pictures / fmt::format("{:06d}.png", f), views, pointers, bodies);
    };
    if (!r.valid()) {
      writePicture();
      continue;
    }
    ++t.tracked;
    report.setFrame(f, "fit_rms_mm", r.fit_rms_m * 1e3);
    report.setFrame(f, "rim_rms_mm", r.rim_rms_m * 1e3);
    report.setFrame(f, "left_out_camera", r.left_out_camera);
    // The body (the generic human or a file's) posed as the nodes pose it, against each camera's
    // silhouette.
    const PoseData message = poseMessageFor(generic.skeleton, tracker.skeleton(), r.pose, r.joints);
    posedBodyMesh(generic, message, body_pose, transforms, positions, normals);
    double frame_iou = 0;
    for (size_t k = 0; k < cameras.size(); ++k) {
      const int c = cameras[k];
      LowResSilhouette& body = bodies[k];
      rasterizeSilhouette(positions, generic.rest.triangles, rig.camera(c), c,
                          options.silhouette_step, body);
      const double iou = silhouetteIou(body, silhouettes[c]);
      t.iou_sum[size_t(c)] += iou;
      frame_iou += iou / double(cameras.size());
    }
    report.setFrame(f, "silhouette_iou", frame_iou);
    writePicture();
    if (!truth.empty()) {
      // The initialising frame itself is reported but not held to the tracking bound.
      const bool counted = initialised || r.state == TrackState::kTracking;
      double sum = 0;
      for (size_t j = 0; j < truth_index.size(); ++j) {
        const Eigen::Vector3d d = r.joints[j] - truth[f][truth_index[j]];
        sum += d.norm();
        if (counted) t.joint_error_m[j] += d.norm(), t.joint_height_m[j] += d.z();
      }
      const double mm = 1e3 * sum / truth_index.size();
      report.setFrame(f, "mpjpe_mm", mm);
      if (counted) t.errors_mm.push_back(mm);
      initialised = true;
    }
  }
  result.skeleton = tracker.skeleton();
  reportTally(t, rig, cameras, tracker, !truth.empty(), frames, report);
  return result;
}

}  // namespace lumistage
