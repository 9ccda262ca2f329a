#include "core/sim/studio_renderer.h"

#include <stdexcept>

#include "core/base/error.h"
#include "core/render/shader_program.h"

namespace lumistage {

struct StudioRenderer::Programs {
  ShaderProgram actor{"studio_actor.vert", "studio_actor.frag"};
  ShaderProgram background{"studio_background.vert", "studio_background.frag"};
};

StudioRenderer::StudioRenderer(const SkinnedMesh& actor)
    : programs_(std::make_unique<Programs>()), vertex_count_(actor.rest.vertexCount()) {
  if (actor.materials.size() != static_cast<size_t>(vertex_count_)) {
    throw std::invalid_argument("StudioRenderer: the actor needs one material per vertex");
  }
  glGenVertexArrays(1, &vao_);
  glGenVertexArrays(1, &background_vao_);
  glGenBuffers(1, &posed_buffer_);
  glGenBuffers(1, &rest_buffer_);
  glGenBuffers(1, &index_buffer_);
  glBindVertexArray(vao_);

  // Static: rest position and material, 4 floats a vertex.
  std::vector<float> rest(4 * vertex_count_);
  for (int v = 0; v < vertex_count_; ++v) {
    for (int k = 0; k < 3; ++k) rest[4 * v + k] = actor.rest.positions(k, v);
    rest[4 * v + 3] = actor.materials[v];
  }
  glBindBuffer(GL_ARRAY_BUFFER, rest_buffer_);
  glBufferData(GL_ARRAY_BUFFER, rest.size() * sizeof(float), rest.data(), GL_STATIC_DRAW);
  glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, 4 * sizeof(float), nullptr);
  glVertexAttribPointer(3, 1, GL_FLOAT, GL_FALSE, 4 * sizeof(float),
                        reinterpret_cast<void*>(3 * sizeof(float)));
  glEnableVertexAttribArray(2);
  glEnableVertexAttribArray(3);

  // Dynamic: posed position and normal, 6 floats a vertex, replaced every frame.
  glBindBuffer(GL_ARRAY_BUFFER, posed_buffer_);
  glBufferData(GL_ARRAY_BUFFER, 6 * sizeof(float) * vertex_count_, nullptr, GL_STREAM_DRAW);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                        reinterpret_cast<void*>(3 * sizeof(float)));
  glEnableVertexAttribArray(0);
  glEnableVertexAttribArray(1);

  std::vector<GLuint> indices;
  indices.reserve(actor.rest.triangles.size() * 3);
  for (const Eigen::Vector3i& t : actor.rest.triangles) {
    for (int k = 0; k < 3; ++k) indices.push_back(static_cast<GLuint>(t[k]));
  }
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, index_buffer_);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, indices.size() * sizeof(GLuint), indices.data(),
               GL_STATIC_DRAW);
  index_count_ = static_cast<GLsizei>(indices.size());
  glBindVertexArray(0);
  setSurface(actor.rest.positions, actor.rest.normals);
}

StudioRenderer::~StudioRenderer() {
  glDeleteBuffers(1, &posed_buffer_);
  glDeleteBuffers(1, &rest_buffer_);
  glDeleteBuffers(1, &index_buffer_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteVertexArrays(1, &background_vao_);
}

void StudioRenderer::setSurface(const Eigen::Matrix3Xf& positions,
                                const Eigen::Matrix3Xf& normals) {
  if (positions.cols() != vertex_count_ || normals.cols() != vertex_count_) {
    throw std::invalid_argument(
        "StudioRenderer::setSurface: vertex count differs from the actor's");
  }
  interleaved_.resize(6 * vertex_count_);
  for (int v = 0; v < vertex_count_; ++v) {
    for (int k = 0; k < 3; ++k) {
      interleaved_[6 * v + k] = positions(k, v);
      interleaved_[6 * v + 3 + k] = normals(k, v);
    }
  }
  glBindBuffer(GL_ARRAY_BUFFER, posed_buffer_);
  glBufferSubData(GL_ARRAY_BUFFER, 0, interleaved_.size() * sizeof(float), interleaved_.data());
}

void StudioRenderer::render(const Camera& camera, const StudioLook& look, uint32_t noise_seed,
                            std::vector<uint8_t>& rgba, bool with_actor) {
  target_.bind(camera.width(), camera.height(), "StudioRenderer");
  glClearColor(0, 0, 0, 0);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);

  const Eigen::Matrix3f R = camera.rotation().cast<float>();
  const Eigen::Vector3f t = camera.translation().cast<float>();
  const Eigen::Vector3f centre = camera.centre().cast<float>();
  const Intrinsics& k = camera.intrinsics();
  const Distortion& d = camera.distortion();
  const float focal_centre[4] = {float(k.fx), float(k.fy), float(k.cx), float(k.cy)};

  // The screen behind, without depth.
  glDisable(GL_DEPTH_TEST);
  const ShaderProgram& background = programs_->background;
  background.use();
  glUniformMatrix3fv(background.uniform("rotation"), 1, GL_FALSE, R.data());
  glUniform3fv(background.uniform("camera_centre"), 1, centre.data());
  glUniform4fv(background.uniform("focal_centre"), 1, focal_centre);
  glUniform2f(background.uniform("image_size"), float(target_.width()), float(target_.height()));
  glUniform1ui(background.uniform("noise_seed"), noise_seed);
  glUniform1f(background.uniform("noise_sigma"), look.noise_sigma);
  glUniform3fv(background.uniform("screen_green"), 1, look.screen_green.data());
  glUniform1f(background.uniform("unevenness"), look.unevenness);
  const bool room = look.backdrop == StudioLook::Backdrop::kRoom;
  glUniform1i(background.uniform("room"), room ? 1 : 0);
  glBindVertexArray(background_vao_);
  glDrawArrays(GL_TRIANGLES, 0, 3);

  // The actor.
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  const ShaderProgram& actor = programs_->actor;
  actor.use();
  glUniformMatrix3fv(actor.uniform("rotation"), 1, GL_FALSE, R.data());  // column-major, as Eigen
  glUniform3fv(actor.uniform("translation"), 1, t.data());
  glUniform4fv(actor.uniform("focal_centre"), 1, focal_centre);
  glUniform1f(actor.uniform("skew"), float(k.skew));
  const float radial[3] = {float(d.k1), float(d.k2), float(d.k3)};
  glUniform1fv(actor.uniform("radial"), 3, radial);
  glUniform2f(actor.uniform("tangential"), float(d.p1), float(d.p2));
  glUniform2f(actor.uniform("image_size"), float(target_.width()), float(target_.height()));
  glUniform2f(actor.uniform("depth_range"), 0.05f, 50.0f);
  glUniform3fv(actor.uniform("camera_centre"), 1, centre.data());
  glUniform1ui(actor.uniform("noise_seed"), noise_seed);
  glUniform1f(actor.uniform("noise_sigma"), look.noise_sigma);
  glUniform1f(actor.uniform("spill"), room ? 0.0f : look.spill);
  glBindVertexArray(vao_);
  if (with_actor) glDrawElements(GL_TRIANGLES, index_count_, GL_UNSIGNED_INT, nullptr);
  glBindVertexArray(0);

  target_.readRgba(rgba);
}

}  // namespace lumistage
