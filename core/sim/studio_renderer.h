#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/body/skinned_mesh.h"
#include "core/geometry/camera.h"
#include "core/render/gl.h"
#include "core/render/render_target.h"

namespace lumistage {

// How the virtual studio looks: the screen's colour and unevenness, spill, noise.
struct StudioLook {
  // What stands behind the actor: a green screen, or a room (a wooden floor, painted walls with
  // posters and a door: a stage that must be keyed on its clean plate, without green spill).
  enum class Backdrop { kGreenScreen, kRoom };
  Backdrop backdrop = Backdrop::kGreenScreen;
  Eigen::Vector3f screen_green = {0.16f, 0.58f, 0.24f};
  float unevenness = 0.12f;  // relative brightness variation of the screen
  float spill =
      1.0f;  // strength of green spill on the actor's grazing surfaces (green screen only)
  float noise_sigma = 2.0f / 255.0f;
};

// Renders the virtual studio's actor against its green screen as a calibrated camera sees it,
// lens distortion included. Owns its GL objects; needs a current OpenGL 4.3 context (EglContext)
// for its whole life. Images are RGBA8, rows top first; alpha is 255 on the actor (the truth
// silhouette) and 0 elsewhere.
class StudioRenderer {
 public:
  // The actor's mesh in its rest pose with per-vertex materials (SkinnedMesh::materials).
  explicit StudioRenderer(const SkinnedMesh& actor);
  ~StudioRenderer();
  StudioRenderer(const StudioRenderer&) = delete;
  StudioRenderer& operator=(const StudioRenderer&) = delete;

  // The posed surface for the next renders (from skinMesh).
  void setSurface(const Eigen::Matrix3Xf& positions, const Eigen::Matrix3Xf& normals);
  // One camera's image; `noise_seed` should differ per camera and frame. Without the actor: the
  // empty stage, as a background model learns it. `rgba` is resized to
  // width*height*4 when its size differs (reuse it: no allocation).
  void render(const Camera& camera, const StudioLook& look, uint32_t noise_seed,
              std::vector<uint8_t>& rgba, bool with_actor = true);

 private:
  struct Programs;
  std::unique_ptr<Programs> programs_;
  GLuint vao_ = 0, background_vao_ = 0;
  GLuint posed_buffer_ = 0, rest_buffer_ = 0, index_buffer_ = 0;
  GLsizei index_count_ = 0;
  int vertex_count_ = 0;
  RenderTarget target_;
  std::vector<float> interleaved_;  // posed positions and normals, reused
};

}  // namespace lumistage
