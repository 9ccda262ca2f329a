#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <vector>

#include "core/body/motion_clip.h"
#include "core/capture/session_writer.h"
#include "core/capture/virtual_gige_cameras.h"
#include "core/render/egl_context.h"
#include "core/sim/studio_config.h"
#include "core/sim/studio_renderer.h"

namespace lumistage {

// One frame of the virtual studio with its ground truth.
struct StudioFrame {
  int index = 0;
  double time_s = 0;
  Pose pose;
  std::vector<Eigen::Vector3d> joints;       // the actor's joints, metres
  TriangleMesh surface;                      // the posed actor surface
  std::vector<std::vector<uint8_t>> images;  // per camera, RGBA8, rows top first
  std::vector<std::vector<uint8_t>> masks;   // per camera, 255 where the actor is
};

// The synthetic stage: an actor (not the generic human) moved by a motion clip and filmed by a
// calibrated rig against a green screen, with everything a real stage cannot give: the true
// joints, surface and silhouettes. Owns a headless OpenGL context (EglContext).
class VirtualStudio {
 public:
  // Builds the actor and the motion (long enough for `frame_count` frames) and the renderer.
  // Throws Error when the motion or the GL context cannot be had.
  VirtualStudio(StudioConfig config, int frame_count);
  ~VirtualStudio();

  const StudioConfig& config() const { return config_; }
  const Rig& rig() const { return config_.rig; }
  const SkinnedMesh& actor() const { return actor_; }
  const MotionClip& clip() const { return clip_; }
  const std::string& rendererDescription() const { return gl_->description(); }

  // Poses the actor for frame `index` and renders every camera. Reuses `frame`'s buffers.
  void renderFrame(int index, StudioFrame& frame);
  // One camera's view of the empty stage (RGBA8), with the noise of `take`: what a background
  // model learns from before the actor walks in.
  void renderEmptyStage(int camera, int take, std::vector<uint8_t>& rgba);

 private:
  StudioConfig config_;
  SkinnedMesh actor_;
  MotionClip clip_;
  std::unique_ptr<EglContext> gl_;
  std::unique_ptr<StudioRenderer> renderer_;
  std::vector<Eigen::Affine3f> transforms_;
};

// The studio's frames as a recorded session (docs/session-format.md): a writer for its rig, pixel
// format, frame rate and actor's joints (source "virtual-studio"), and each rendered frame written
// with its truth, at its time in the clip. Throw Error as SessionWriter does.
std::unique_ptr<SessionWriter> openStudioSession(const VirtualStudio& studio,
                                                 const std::filesystem::path& folder);
// `frames` frames of the empty stage from every camera, as the session's plate
// (SessionWriter::writePlate): what nodes key a stage without a green screen on.
void writeStudioPlate(VirtualStudio& studio, int frames, SessionWriter& writer);
// `images` is scratch, reused.
void writeStudioFrame(const VirtualStudio& studio, const StudioFrame& frame, int64_t frame_id,
                      SessionWriter& writer, std::vector<Image>& images);

// All views of a frame in a grid, a quarter of their size, each labelled with its camera and node,
// written as a PNG (atomically) to look at. Throws Error naming the file when it cannot be written.
void writeContactSheet(const Rig& rig, const StudioFrame& frame, const std::filesystem::path& png);

// Renders frames 0..frame_count-1 of the studio into a loop for virtual cameras, in `format`.
// `progress(done, total)` is called after each frame.
FrameLoop renderFrameLoop(VirtualStudio& studio, int frame_count, PixelFormat format,
                          const std::function<void(int, int)>& progress = {});

}  // namespace lumistage
