#include "core/sim/stage_draw.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "core/base/error.h"
#include "core/body/bvh.h"
#include "core/body/human_skeleton.h"
#include "core/body/motion_library.h"
#include "core/geometry/ring_rig.h"

namespace lumistage {

namespace {

constexpr double kPi = std::numbers::pi;

// Numbers from a seed, the same on every standard library: mt19937's sequence is fixed by the
// standard, its distributions are not.
class Dice {
 public:
  explicit Dice(uint32_t seed) : engine_(seed) {}
  double uniform(double lo, double hi) {
    const double u = double(engine_() >> 5) * 0x1p-27;  // 27 bits in [0, 1)
    return lo + (hi - lo) * u;
  }
  int integer(int lo, int hi) {  // both included
    return lo + int(uniform(0, 1) * (hi - lo + 1));
  }
  bool chance(double p) { return uniform(0, 1) < p; }

 private:
  std::mt19937 engine_;
};

// The column every camera must see whole: wherever the drawn motion takes the actor (root within
// kRoamM of the centre), arms out and raised.
constexpr double kColumnRadiusM = 1.0, kColumnTopM = 2.5, kRoamM = 0.8;

// The focal length that fits the column into a width x height image whose principal point is
// (cx, cy), with a margin of `margin` of the image on every side, undistorted (the drawn lenses
// move the column's edge by a few pixels at most, inside the margin).
double fittingFocal(const Eigen::Matrix3d& R, const Eigen::Vector3d& centre, int width, int height,
                    double cx, double cy, double margin) {
  double focal = 1e9;
  for (int a = 0; a < 48; ++a) {
    for (int h = 0; h <= 10; ++h) {
      const Eigen::Vector3d p(kColumnRadiusM * std::cos(2 * kPi * a / 48),
                              kColumnRadiusM * std::sin(2 * kPi * a / 48), kColumnTopM * h / 10);
      const Eigen::Vector3d q = R * (p - centre);
      if (q.z() <= 0.1) continue;  // behind: the rig is drawn so that nothing is
      const double x = q.x() / q.z(), y = q.y() / q.z();
      const double room_x = x > 0 ? (1 - margin) * width - cx : cx - margin * width;
      const double room_y = y > 0 ? (1 - margin) * height - cy : cy - margin * height;
      if (std::abs(x) > 1e-9) focal = std::min(focal, room_x / std::abs(x));
      if (std::abs(y) > 1e-9) focal = std::min(focal, room_y / std::abs(y));
    }
  }
  return focal;
}

Rig drawRig(Dice& dice, const StageDrawOptions& options) {
  const int n = dice.integer(options.min_cameras, options.max_cameras);
  const bool ring = dice.chance(0.5);
  static constexpr int kSizes[][2] = {{1280, 720}, {1024, 768}, {1280, 960}, {1280, 1024}};
  const auto& size = kSizes[dice.integer(0, 3)];
  const int width = size[0], height = size[1];
  const double radius = dice.uniform(3.2, 4.5);
  const double phase = dice.uniform(0, 2 * kPi);
  std::vector<double> levels(dice.integer(1, 3));
  for (double& level : levels) level = dice.uniform(0.5, 3.0);
  const Eigen::Vector3d target(dice.uniform(-0.2, 0.2), dice.uniform(-0.2, 0.2),
                               dice.uniform(0.8, 1.2));
  std::vector<Camera> cameras;
  for (int i = 0; i < n; ++i) {
    double angle = phase + 2 * kPi * i / n, r = radius, z = levels[i % levels.size()];
    if (!ring) {
      angle += dice.uniform(-0.4, 0.4) * 2 * kPi / n;
      r *= dice.uniform(0.85, 1.12);
      z = dice.uniform(0.5, 3.0);
    }
    const Eigen::Vector3d centre(r * std::cos(angle), r * std::sin(angle), z);
    const Eigen::Vector3d aim =
        target +
        Eigen::Vector3d(dice.uniform(-0.1, 0.1), dice.uniform(-0.1, 0.1), dice.uniform(-0.1, 0.1));
    const Eigen::Matrix3d R = aimedRotation(centre, aim);
    const double cx = 0.5 * (width - 1) + dice.uniform(-14, 14);
    const double cy = 0.5 * (height - 1) + dice.uniform(-10, 10);
    const double f = fittingFocal(R, centre, width, height, cx, cy, 0.03);
    const Intrinsics intrinsics{f, f * dice.uniform(0.998, 1.002), cx, cy, 0.0};
    const Distortion distortion{dice.uniform(-0.15, 0.03), dice.uniform(-0.02, 0.05),
                                dice.uniform(-5e-4, 5e-4), dice.uniform(-5e-4, 5e-4), 0.0};
    cameras.emplace_back(fmt::format("cam{:02}", i + 1), width, height, intrinsics, distortion, R,
                         -R * centre);
  }
  // Nodes of 1 to 4 cameras, each a random handful of the ring.
  std::vector<int> order(n);
  for (int i = 0; i < n; ++i) order[i] = i;
  for (int i = n - 1; i > 0; --i) std::swap(order[i], order[dice.integer(0, i)]);
  std::vector<RigNode> nodes;
  for (int next = 0; next < n;) {
    const int count = std::min(n - next, dice.integer(1, 4));
    RigNode node{fmt::format("node{}", nodes.size() + 1), "", {}};
    node.cameras.assign(order.begin() + next, order.begin() + next + count);
    std::sort(node.cameras.begin(), node.cameras.end());
    nodes.push_back(std::move(node));
    next += count;
  }
  Rig rig(std::move(cameras), std::move(nodes));
  rig.setStage(StageBox{{-1.5, -1.5, 0.0}, {1.5, 1.5, 2.6}});
  return rig;
}

HumanModelSpec drawActor(Dice& dice) {
  HumanModelSpec actor;
  BodyShape& shape = actor.shape;
  shape.height_m = dice.uniform(1.50, 2.05);
  shape.arm_length_scale = dice.uniform(0.93, 1.07);
  shape.leg_length_scale = dice.uniform(0.93, 1.07);
  shape.shoulder_width_scale = dice.uniform(0.9, 1.12);
  shape.hip_width_scale = dice.uniform(0.92, 1.15);
  shape.girth_scale = dice.uniform(0.9, 1.35);
  shape.belly_scale = dice.uniform(0.9, 1.6);
  actor.clothing = dice.chance(0.8);
  actor.target_vertices = 8000;
  return actor;
}

// The motion, where it starts and where it plays: centred, turned, and moved off-centre as far as
// its root then stays within kRoamM of the centre.
void drawMotion(Dice& dice, const StageDrawOptions& options, StudioConfig& config) {
  std::vector<std::string> clips = options.clips.empty() ? builtinClipNames() : options.clips;
  const int choices = int(clips.size() + options.bvh_files.size());
  if (choices == 0) throw Error("stage draw: no motion to draw from");
  const int pick = dice.integer(0, choices - 1);
  const Skeleton skeleton = makeHumanSkeleton(config.actor.shape);
  const double session_s = (options.frames - 1) / options.fps;
  MotionClip clip;
  MotionPlacement& placement = config.placement;
  if (pick < int(clips.size())) {
    config.clip = clips[pick];
    // The built-in clips are made as long as asked (as VirtualStudio makes them): up to 3 s in.
    placement.start_s = options.any_start ? dice.uniform(0, 3) : 0;
    clip = makeBuiltinClip(config.clip, skeleton, options.fps,
                           std::max(1.0, placement.start_s + options.frames / options.fps));
  } else {
    config.bvh_file = options.bvh_files[pick - clips.size()];
    clip = loadBvh(config.bvh_file, skeleton);
    const double room = clip.durationSeconds() - session_s;
    if (room < 0)
      throw Error(fmt::format("{}: {:.2f} s long, shorter than the session ({:.2f} s)",
                              config.bvh_file.string(), clip.durationSeconds(), session_s));
    placement.start_s = options.any_start ? dice.uniform(0, room) : 0;
  }
  placement.centre = true;
  placement.heading_deg = dice.uniform(0, 360);
  MotionClip centred = clip;
  MotionPlacement centring;
  centring.start_s = placement.start_s;
  centring.centre = true;
  placeMotion(centred, skeleton, centring, options.frames, options.fps);
  double reach = 0;
  for (int f = 0; f < options.frames; ++f)
    reach = std::max(reach, (skeleton.joint(0).offset_m +
                             centred.sample(placement.start_s + f / options.fps).root_translation_m)
                                .head<2>()
                                .norm());
  const double distance = std::max(0.0, std::min(dice.uniform(0, 0.6), kRoamM - reach));
  const double direction = dice.uniform(0, 2 * kPi);
  placement.offset_m = distance * Eigen::Vector2d(std::cos(direction), std::sin(direction));
  config.fps = options.fps;
}

StudioLook drawLook(Dice& dice, PixelFormat& format) {
  StudioLook look;
  look.screen_green = {float(dice.uniform(0.08, 0.25)), float(dice.uniform(0.45, 0.7)),
                       float(dice.uniform(0.12, 0.35))};
  look.unevenness = float(dice.uniform(0.04, 0.22));
  look.spill = float(dice.uniform(0.3, 1.3));
  look.noise_sigma = float(dice.uniform(1, 4) / 255);
  static constexpr PixelFormat kFormats[] = {PixelFormat::kRgb8, PixelFormat::kBayerRggb8,
                                             PixelFormat::kBayerGrbg8, PixelFormat::kBayerGbrg8,
                                             PixelFormat::kBayerBggr8};
  format = kFormats[dice.integer(0, 4)];
  return look;
}

}  // namespace

std::vector<std::filesystem::path> bvhFilesIn(const std::filesystem::path& folder) {
  std::error_code ec;
  if (!std::filesystem::is_directory(folder, ec)) throw Error(folder.string() + ": not a folder");
  std::vector<std::filesystem::path> files;
  for (const std::filesystem::directory_entry& entry :
       std::filesystem::directory_iterator(folder, ec)) {
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext == ".bvh") files.push_back(entry.path());
  }
  if (ec) throw Error(folder.string() + ": " + ec.message());
  std::sort(files.begin(), files.end());
  return files;
}

StudioConfig drawStage(uint32_t seed, const StageDrawOptions& options) {
  if (options.min_cameras < 2 || options.max_cameras < options.min_cameras ||
      options.max_cameras > 64)
    throw Error(fmt::format("stage draw: cameras {}-{}: expected 2 <= min <= max <= 64",
                            options.min_cameras, options.max_cameras));
  if (options.frames < 1 || !(options.fps > 0))
    throw Error("stage draw: expected at least one frame and a positive frame rate");
  // Each part from a generator of its own, so that limiting one (the cameras, the motions) leaves
  // the others as they were for the same seed.
  const auto part = [seed](uint32_t salt) { return Dice(seed * 2654435761u ^ salt); };
  StudioConfig config;
  config.seed = seed;
  Dice rig = part(0x51a9e), actor = part(0xac70), motion = part(0x3071), look = part(0x100c);
  config.rig = drawRig(rig, options);
  config.actor = drawActor(actor);
  drawMotion(motion, options, config);
  config.look = drawLook(look, config.pixel_format);
  return config;
}

std::string describeStage(const StudioConfig& config) {
  const Rig& rig = config.rig;
  double lowest = 1e9, highest = -1e9;
  for (const Camera& camera : rig.cameras()) {
    lowest = std::min(lowest, camera.centre().z());
    highest = std::max(highest, camera.centre().z());
  }
  const MotionPlacement& p = config.placement;
  const std::string motion =
      config.bvh_file.empty() ? config.clip : config.bvh_file.filename().string();
  return fmt::format(
      "{} cameras {}x{} on {} nodes, {:.1f}-{:.1f} m high; actor {:.2f} m, girth {:.2f}{}; "
      "{} from {:.1f} s, heading {:.0f} deg, {:.2f} m off centre; {}",
      rig.cameraCount(), rig.camera(0).width(), rig.camera(0).height(), rig.nodeCount(), lowest,
      highest, config.actor.shape.height_m, config.actor.shape.girth_scale,
      config.actor.clothing ? ", clothed" : "", motion, p.start_s, p.heading_deg, p.offset_m.norm(),
      pixelFormatName(config.pixel_format));
}

}  // namespace lumistage
