#include "app/cli/render_command.h"

#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <numbers>

#include "app/cli/checks.h"
#include "app/cli/progress.h"
#include "core/base/error.h"
#include "core/base/output_path.h"
#include "core/base/stop_signal.h"
#include "core/body/ply_mesh.h"
#include "core/capture/session_reader.h"
#include "core/eval/leave_one_out.h"
#include "core/imaging/clean_plate.h"
#include "core/render/clone_set.h"
#include "core/render/egl_context.h"
#include "core/render/frame_inputs.h"
#include "core/render/lumigraph_renderer.h"
#include "core/render/silhouette_feather.h"
#include "core/render/video_file.h"
#include "core/render/view_recorder.h"

namespace lumistage {

namespace {

// The virtual camera of path `path` at t in [0, 1): "orbit" circles the stage 3.5 m out and
// 1.6 m up looking at 1 m above its centre, once over the video; "camNN" stays on that camera.
Camera pathCamera(const std::string& path, const Rig& rig, double t, int width, int height) {
  if (const std::optional<int> c = rig.findCamera(path)) {
    const Camera& cam = rig.camera(*c);
    const double s = double(width) / cam.width();
    Intrinsics k = cam.intrinsics();
    k.fx *= s, k.fy *= s, k.skew *= s;
    k.cx = (k.cx + 0.5) * s - 0.5, k.cy = (k.cy + 0.5) * s - 0.5;
    return Camera("view", width, int(std::lround(cam.height() * s)), k, cam.distortion(),
                  cam.rotation(), cam.translation());
  }
  if (path != "orbit") throw Error("--path: 'orbit' or a camera of the rig expected, not " + path);
  const double a = 2 * std::numbers::pi * t - 0.75 * std::numbers::pi;
  const Eigen::Vector3d centre(3.5 * std::cos(a), 3.5 * std::sin(a), 1.6), target(0, 0, 1.0);
  const Eigen::Vector3d z = (target - centre).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  Eigen::Matrix3d R;
  R.row(0) = x, R.row(1) = z.cross(x), R.row(2) = z;
  const double f = 0.9 * width;  // about 58 degrees across
  return Camera("view", width, height, {f, f, width / 2.0 - 0.5, height / 2.0 - 0.5, 0}, {}, R,
                -R * centre);
}

}  // namespace

void addRenderCommand(CLI::App& app) {
  struct Args {
    std::string session, path = "orbit", out, mesh = "truth";
    int width = 1280, height = 720, frames = 0, clones = 1;
    double fps = 0;
  };
  auto a = std::make_shared<Args>();
  CLI::App* render = app.add_subcommand(
      "render", "Render a camera path through a recorded session into a video (lumigraph)");
  render->add_option("--session", a->session, "recorded session")->required();
  render->add_option("--path", a->path, "camera path: orbit, or a camera's name")
      ->capture_default_str();
  render->add_option("--out", a->out, "video file: .mp4 (H.264) or .avi (Motion-JPEG)")->required();
  render
      ->add_option("--mesh", a->mesh,
                   "geometry: truth (the session's truth/surface) or a folder of NNNNNN.ply")
      ->capture_default_str();
  render->add_option("--width", a->width)->check(within(16, 7680))->capture_default_str();
  render->add_option("--height", a->height)->check(within(16, 4320))->capture_default_str();
  render->add_option("--frames", a->frames, "frames to render (default: the session's)")
      ->check(within(1, 1e9));
  render->add_option("--fps", a->fps, "video rate (default: the session's)")
      ->check(within(1, 1000));
  render->add_option("--clones", a->clones, "copies of the actor side by side, 1 m apart")
      ->check(CLI::Range(1, CloneSet::kMaxClones))
      ->capture_default_str();
  render->callback([a] {
    refuseOutputOverInputs("--out", a->out, {{"--session", a->session}});
    const std::filesystem::path out(a->out);
    const VideoCodec codec = videoCodecFor(out);  // .mp4 H.264, .avi Motion-JPEG
    requireOutputFolder("--out", out);
    const SessionReader session(a->session);
    const Rig& rig = session.rig();
    const int frames =
        a->frames > 0 ? std::min(a->frames, session.frameCount()) : session.frameCount();
    if (frames == 0) throw Error(a->session + ": no frames");
    EglContext gl;
    std::vector<int> all(rig.cameraCount());
    for (int c = 0; c < rig.cameraCount(); ++c) all[c] = c;
    LumigraphParams params;
    params.phong_subdivision = a->mesh != "truth";  // the true surface is finely tessellated
    LumigraphRenderer renderer(rig, all, params);
    std::vector<Eigen::Affine3f> clones;
    for (int i = 0; i < a->clones; ++i) {
      Eigen::Affine3f t = Eigen::Affine3f::Identity();
      t.translate(Eigen::Vector3f(float(i - (a->clones - 1) / 2.0), 0, 0));
      clones.push_back(t);
    }
    const Camera first = pathCamera(a->path, rig, 0, a->width, a->height);
    // The video is made beside its name (the same extension: it chooses the container) and
    // renamed over it once it reads back whole: a failed frame, a full disk or an interrupted
    // render never replaces a good video with a torn one.
    const std::filesystem::path partial = partialVideoPath(out);
    struct RemovePartial {
      const std::filesystem::path& path;
      bool keep = false;
      ~RemovePartial() {
        std::error_code ignored;
        if (!keep) std::filesystem::remove(path, ignored);
      }
    } remove_partial{partial};
    VideoFileWriter video(partial, first.width(), first.height(),
                          a->fps > 0 ? a->fps : session.fps(), codec);
    if (!video.warning().empty()) fmt::print(stderr, "lumistage render: {}\n", video.warning());
    fmt::print("rendering {} frames of {}x{} on {}\n", frames, first.width(), first.height(),
               gl.description());
    std::vector<CameraFrame> images;
    FrameInputs inputs;
    inputs.setPlates(sessionPlates(session));
    std::vector<uint8_t> rgba;
    double ms = -1;
    // Ctrl-C (SIGTERM, SIGHUP) ends the render between frames: the video begun is removed, and an
    // older one of that name is left as it was.
    const std::atomic<bool>& stop = stopOnSignals();
    for (int i = 0; i < frames; ++i) {
      if (stop) {
        if (isatty(STDERR_FILENO)) fmt::print(stderr, "\n");  // below the progress bar
        throw Error(fmt::format(
            "stopped by {} after {} of {} frames: {}", stopSignalName(stopSignal()), i, frames,
            std::filesystem::exists(out) ? "the old file is left as it was" : "nothing written"));
      }
      const auto start = std::chrono::steady_clock::now();
      session.readFrame(i, images);
      inputs.set(renderer, images);  // images and foreground masks, as the nodes give theirs
      const TriangleMesh mesh = a->mesh == "truth"
                                    ? truthSurface(session, i)
                                    : readPlyMesh(std::filesystem::path(a->mesh) /
                                                  fmt::format("{:06}.ply", session.frameId(i)));
      renderer.setMesh(mesh.positions, mesh.normals, mesh.triangles);
      const Camera view = pathCamera(a->path, rig, double(i) / frames, a->width, a->height);
      renderer.render(view, clones, rgba);
      finishSingleProcessView(rgba, view.width(), view.height());  // as the studio shows a view
      video.write(rgba.data(), PixelOrder::kRgba);
      const double took =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count();
      ms = ms < 0 ? took : 0.9 * ms + 0.1 * took;
      printProgress("render", i + 1, frames, ms);
    }
    video.close();
    if (const Status finished = finishPartialVideo(partial, out, frames); !finished.ok()) {
      throw Error(
          finished.error() + "; " +
          (std::filesystem::exists(out) ? "the old file is left as it was" : "nothing written"));
    }
    remove_partial.keep = true;
    fmt::print("wrote {}\n", a->out);
  });
}

}  // namespace lumistage
