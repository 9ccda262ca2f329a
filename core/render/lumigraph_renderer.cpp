#include "core/render/lumigraph_renderer.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "core/base/error.h"
#include "core/render/egl_context.h"
#include "core/render/partial_image_blender.h"
#include "core/render/shader_program.h"

namespace lumistage {

namespace {
constexpr int kVertexFloats = 7;  // position, normal, rim dilation

// The blend shaders' constants: the rig's camera count and the own cameras' rig indices, so that
// every loop over cameras has a fixed count and every own camera a fixed index (llvmpipe runs
// the vertex shader on one thread; unrolled, it does a third less work).
std::string blendDefines(int cameras, const std::vector<int>& own) {
  std::string list;
  for (int c : own) list += (list.empty() ? "" : ", ") + std::to_string(c);
  return "#define kCameras " + std::to_string(cameras) + "\n#define kOwnCameras " +
         std::to_string(own.size()) + "\n#define kOwnCameraList " + list +
         "\n#define kAlphaStepsPerOctave " + std::to_string(kAlphaStepsPerOctave);
}

}  // namespace

struct LumigraphRenderer::Programs {
  Programs(int cameras, const std::vector<int>& own)
      : defines(blendDefines(cameras, own)), blend("lumigraph.vert", "lumigraph.frag", defines) {}
  std::string defines;
  ShaderProgram blend;                    // compiled for the renderer's rig and own cameras
  std::unique_ptr<ShaderProgram> mosaic;  // the same with Bayer mosaics, once they come
};

namespace {

struct CameraUniforms {
  Eigen::Matrix3f rotation;
  Eigen::Vector3f translation, centre, radial;
  float focal_centre[4];
  float skew;
  float tangential[2];
  float size[2];
};

CameraUniforms uniformsOf(const Camera& camera) {
  CameraUniforms u;
  u.rotation = camera.rotation().cast<float>();
  u.translation = camera.translation().cast<float>();
  u.centre = camera.centre().cast<float>();
  const Intrinsics& k = camera.intrinsics();
  const Distortion& d = camera.distortion();
  u.radial = Eigen::Vector3f(float(d.k1), float(d.k2), float(d.k3));
  u.focal_centre[0] = float(k.fx), u.focal_centre[1] = float(k.fy);
  u.focal_centre[2] = float(k.cx), u.focal_centre[3] = float(k.cy);
  u.skew = float(k.skew);
  u.tangential[0] = float(d.p1), u.tangential[1] = float(d.p2);
  u.size[0] = float(camera.width()), u.size[1] = float(camera.height());
  return u;
}

// The desired camera's uniforms.
void setDesiredCamera(const ShaderProgram& p, const CameraUniforms& u) {
  glUniformMatrix3fv(p.uniform("view_rotation"), 1, GL_FALSE, u.rotation.data());
  glUniform3fv(p.uniform("view_translation"), 1, u.translation.data());
  glUniform4fv(p.uniform("view_focal_centre"), 1, u.focal_centre);
  glUniform1f(p.uniform("view_skew"), u.skew);
  glUniform3fv(p.uniform("view_radial"), 1, u.radial.data());
  glUniform2fv(p.uniform("view_tangential"), 1, u.tangential);
  glUniform2fv(p.uniform("view_size"), 1, u.size);
}

}  // namespace

LumigraphRenderer::LumigraphRenderer(const Rig& rig, std::vector<int> own, LumigraphParams params)
    : rig_(rig),
      own_(std::move(own)),
      params_(params),
      active_(rig.cameraCount(), 1),
      mosaic_red_(own_.size(), Eigen::Vector2i::Zero()),
      mosaic_sizes_(own_.size(), Eigen::Vector2i::Ones()),
      despill_(own_.size(), 0.0f) {
  if (rig_.cameraCount() > kMaxCameras || rig_.cameraCount() == 0) {
    throw Error("LumigraphRenderer: the rig has " + std::to_string(rig_.cameraCount()) +
                " cameras; 1 to " + std::to_string(kMaxCameras) + " are supported");
  }
  for (int c : own_) {
    if (c < 0 || c >= rig_.cameraCount())
      throw Error("LumigraphRenderer: own camera " + std::to_string(c) + " is not in the rig");
  }
  if (own_.empty() || own_.size() > size_t(kMaxCameras))
    throw Error("LumigraphRenderer: 1 to " + std::to_string(kMaxCameras) + " own cameras needed");
  programs_ = std::make_unique<Programs>(rig_.cameraCount(), own_);
  params_.k = std::clamp(params_.k, 1, 4);
  if (params_.bayer_images == LumigraphParams::BayerImages::kAuto) {
    params_.bayer_images = currentRendererIsSoftware()
                               ? LumigraphParams::BayerImages::kCells
                               : LumigraphParams::BayerImages::kFullResolution;
  }
  params_.depth_map_divisor = std::max(1, params_.depth_map_divisor);
  for (const Camera& c : rig_.cameras()) {
    images_width_ = std::max(images_width_, c.width());
    images_height_ = std::max(images_height_, c.height());
  }

  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &vertex_buffer_);
  glGenBuffers(1, &index_buffer_);
  glGenBuffers(1, &upload_buffer_);
  glGenBuffers(1, &visibility_buffer_);
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vertex_buffer_);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, kVertexFloats * sizeof(float), nullptr);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, kVertexFloats * sizeof(float),
                        reinterpret_cast<void*>(3 * sizeof(float)));
  glVertexAttribPointer(2, 1, GL_FLOAT, GL_FALSE, kVertexFloats * sizeof(float),
                        reinterpret_cast<void*>(6 * sizeof(float)));
  glEnableVertexAttribArray(0);
  glEnableVertexAttribArray(1);
  glEnableVertexAttribArray(2);
  glBindBuffer(GL_ARRAY_BUFFER, visibility_buffer_);
  glVertexAttribIPointer(3, 1, GL_UNSIGNED_INT, sizeof(CameraMask), nullptr);
  glEnableVertexAttribArray(3);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, index_buffer_);
  glBindVertexArray(0);
}

LumigraphRenderer::~LumigraphRenderer() {
  glDeleteTextures(1, &images_);
  glDeleteTextures(1, &masks_);
  glDeleteBuffers(1, &vertex_buffer_);
  glDeleteBuffers(1, &index_buffer_);
  glDeleteBuffers(1, &upload_buffer_);
  glDeleteBuffers(1, &visibility_buffer_);
  glDeleteVertexArrays(1, &vao_);
}

void LumigraphRenderer::setMesh(const Eigen::Matrix3Xf& positions, const Eigen::Matrix3Xf& normals,
                                std::span<const Eigen::Vector3i> triangles,
                                std::span<const CameraMask> visibility) {
  const int n = static_cast<int>(positions.cols());
  if (normals.cols() != n) throw Error("LumigraphRenderer::setMesh: one normal per vertex needed");
  if (visibility.empty()) {
    visibility_.compute(rig_, positions, triangles, params_.depth_map_divisor,
                        params_.depth_tolerance_m);
    visibility = visibility_.masks();
  }
  if (visibility.size() != size_t(n))
    throw Error("LumigraphRenderer::setMesh: " + std::to_string(visibility.size()) +
                " visibility masks for " + std::to_string(n) + " vertices");
  if (params_.phong_subdivision) {
    subdivision_.subdivide(positions, normals, triangles, visibility);
    upload(subdivision_.positions(), subdivision_.normals(), subdivision_.triangles(),
           subdivision_.masks());
  } else {
    upload(positions, normals, triangles, visibility);
  }
}

void LumigraphRenderer::upload(const Eigen::Matrix3Xf& positions, const Eigen::Matrix3Xf& normals,
                               std::span<const Eigen::Vector3i> triangles,
                               std::span<const CameraMask> visibility) {
  const int n = static_cast<int>(positions.cols());
  mesh_centre_ =
      n > 0 ? Eigen::Vector3f(positions.rowwise().sum() / float(n)) : Eigen::Vector3f::Zero();
  // Rim dilation: the mean sagitta of each vertex's edges, (-n_v . (p_u - p_v)) / 4 for an edge
  // v-u where the surface bends away (convex), 0 where it bends toward the normal.
  rim_sum_.assign(n, 0.0f);
  rim_count_.assign(n, 0);
  if (params_.rim_dilation > 0) {
    for (const Eigen::Vector3i& t : triangles) {
      if (t.minCoeff() < 0 || t.maxCoeff() >= n) continue;
      for (int e = 0; e < 3; ++e) {
        const int a = t[e], b = t[(e + 1) % 3];
        const Eigen::Vector3f d = positions.col(b) - positions.col(a);
        rim_sum_[a] += std::max(0.0f, -normals.col(a).dot(d)) * 0.25f;
        rim_sum_[b] += std::max(0.0f, normals.col(b).dot(d)) * 0.25f;
        ++rim_count_[a];
        ++rim_count_[b];
      }
    }
  }
  // Drawn in an order that shades each vertex about once (DrawOrder).
  const bool new_order = draw_order_.build(n, triangles);
  const std::vector<int>& order = draw_order_.order();
  triangles = draw_order_.triangles();
  vertices_.resize(size_t(kVertexFloats) * n);
  if (!visibility.empty()) {
    ordered_visibility_.resize(n);
    for (int i = 0; i < n; ++i) ordered_visibility_[i] = visibility[order[i]];
    visibility = ordered_visibility_;
  }
  for (int i = 0; i < n; ++i) {
    const int v = order[i];
    float* out = &vertices_[size_t(kVertexFloats) * i];
    for (int k = 0; k < 3; ++k) {
      out[k] = positions(k, v);
      out[3 + k] = normals(k, v);
    }
    out[6] = rim_count_[v] > 0 ? params_.rim_dilation * rim_sum_[v] / float(rim_count_[v]) : 0.0f;
  }
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vertex_buffer_);
  const GLsizeiptr vertex_bytes = GLsizeiptr(vertices_.size() * sizeof(float));
  if (vertex_bytes > vertex_capacity_) {
    glBufferData(GL_ARRAY_BUFFER, vertex_bytes, nullptr, GL_STREAM_DRAW);
    vertex_capacity_ = vertex_bytes;
  }
  glBufferSubData(GL_ARRAY_BUFFER, 0, vertex_bytes, vertices_.data());
  static_assert(sizeof(Eigen::Vector3i) == 3 * sizeof(GLuint));
  const GLsizeiptr index_bytes = GLsizeiptr(triangles.size() * sizeof(Eigen::Vector3i));
  // The indices change with the topology alone (the element buffer is the vertex array's).
  const bool grown = index_bytes > index_capacity_;
  if (grown) {
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, index_bytes, nullptr, GL_STATIC_DRAW);
    index_capacity_ = index_bytes;
  }
  if (index_bytes > 0 && (new_order || grown))
    glBufferSubData(GL_ELEMENT_ARRAY_BUFFER, 0, index_bytes, triangles.data());
  index_count_ = static_cast<GLsizei>(triangles.size() * 3);
  glBindBuffer(GL_ARRAY_BUFFER, visibility_buffer_);
  const GLsizeiptr visibility_bytes = GLsizeiptr(visibility.size() * sizeof(CameraMask));
  if (visibility_bytes > visibility_capacity_) {
    glBufferData(GL_ARRAY_BUFFER, visibility_bytes, nullptr, GL_STREAM_DRAW);
    visibility_capacity_ = visibility_bytes;
  }
  if (visibility_bytes > 0)
    glBufferSubData(GL_ARRAY_BUFFER, 0, visibility_bytes, visibility.data());
  glBindVertexArray(0);
}

void LumigraphRenderer::setImage(int own_index, const ImageView& image) {
  if (own_index < 0 || own_index >= static_cast<int>(own_.size()))
    throw Error("LumigraphRenderer::setImage: no own camera " + std::to_string(own_index));
  if (image.format == PixelFormat::kRgb8) {
    // Widened to RGBA (RGB uploads are slow: never RGB).
    const size_t n = size_t(image.width) * image.height;
    staging_.resize(n * 4);
    rgbToRgba(image.data, n, staging_.data());
    useImageFormat(ImageTexture::kRgba);
    uploadImage(own_index, image.width, image.height, staging_.data());
    return;
  }
  if (image.format == PixelFormat::kMono8) {
    // Grey, pixel by pixel (read as Bayer cells, an edge between grey pixels took false colour).
    const size_t n = size_t(image.width) * image.height;
    staging_.resize(n * 4);
    for (size_t i = 0; i < n; ++i) {
      const uint8_t v = image.data[i];
      staging_[4 * i] = staging_[4 * i + 1] = staging_[4 * i + 2] = v;
      staging_[4 * i + 3] = 255;
    }
    useImageFormat(ImageTexture::kRgba);
    uploadImage(own_index, image.width, image.height, staging_.data());
    return;
  }
  if (params_.bayer_images == LumigraphParams::BayerImages::kFullResolution) {
    // The mosaic as it is, demosaiced by the shader.
    const BayerLayout layout = bayerLayout(image.format);
    mosaic_red_[own_index] = Eigen::Vector2i(layout.red_x, layout.red_y);
    mosaic_sizes_[own_index] = Eigen::Vector2i(image.width, image.height);
    useImageFormat(ImageTexture::kMosaic);
    uploadImage(own_index, image.width, image.height, image.data);
    return;
  }
  // Bayer: a 2x2 cell's colour a texel.
  staging_.resize(size_t(image.width / 2) * (image.height / 2) * 4);
  bayerCellsToRgba(image, staging_.data());
  useImageFormat(ImageTexture::kCells);
  uploadImage(own_index, image.width / 2, image.height / 2, staging_.data());
}

void LumigraphRenderer::setImageRgba(int own_index, const uint8_t* rgba, int width, int height) {
  if (own_index < 0 || own_index >= static_cast<int>(own_.size()))
    throw Error("LumigraphRenderer::setImage: no own camera " + std::to_string(own_index));
  useImageFormat(ImageTexture::kRgba);
  uploadImage(own_index, width, height, rgba);
}

void LumigraphRenderer::setMask(int own_index, std::span<const uint8_t> mask, int width,
                                int height) {
  if (own_index < 0 || own_index >= static_cast<int>(own_.size()) || width <= 0 || height <= 0 ||
      mask.size() != size_t(width) * height)
    throw Error("LumigraphRenderer::setMask: own camera " + std::to_string(own_index) + ", a " +
                std::to_string(width) + "x" + std::to_string(height) + " mask of " +
                std::to_string(mask.size()) + " bytes");
  glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  const Eigen::Vector2i mask_cells(width, height);
  // One array for every own camera's mask, each in the corner of its layer: sized to the largest
  // given (cameras of different sizes), grown when a larger one comes (the other layers then read
  // "all in" until given again: every frame gives them all).
  if (!masks_ || width > mask_width_ || height > mask_height_) {
    width = std::max(width, mask_width_), height = std::max(height, mask_height_);
    glDeleteTextures(1, &masks_);
    glGenTextures(1, &masks_);
    glBindTexture(GL_TEXTURE_2D_ARRAY, masks_);
    const GLsizei layers = static_cast<GLsizei>(own_.size());
    glTexStorage3D(GL_TEXTURE_2D_ARRAY, 1, GL_R8, width, height, layers);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    const std::vector<uint8_t> all(size_t(width) * height * layers, 255);  // not given: all in
    glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, 0, width, height, layers, GL_RED,
                    GL_UNSIGNED_BYTE, all.data());
    mask_width_ = width, mask_height_ = height;
    mask_sizes_.assign(own_.size(), Eigen::Vector2i::Zero());
    width = mask_cells.x(), height = mask_cells.y();
  }
  glBindTexture(GL_TEXTURE_2D_ARRAY, masks_);
  glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, own_index, width, height, 1, GL_RED,
                  GL_UNSIGNED_BYTE, mask.data());
  mask_sizes_[own_index] = mask_cells;
}

void LumigraphRenderer::useImageFormat(ImageTexture kind) {
  if (images_ && image_texture_ == kind) return;
  if (kind == ImageTexture::kMosaic && !programs_->mosaic) {
    programs_->mosaic = std::make_unique<ShaderProgram>("lumigraph.vert", "lumigraph.frag",
                                                        programs_->defines + "\n#define kMosaic");
  }
  glDeleteTextures(1, &images_);
  glGenTextures(1, &images_);
  glBindTexture(GL_TEXTURE_2D_ARRAY, images_);
  const int divisor = kind == ImageTexture::kCells ? 2 : 1;
  glTexStorage3D(GL_TEXTURE_2D_ARRAY, 1, kind == ImageTexture::kMosaic ? GL_R8 : GL_RGBA8,
                 std::max(1, images_width_ / divisor), std::max(1, images_height_ / divisor),
                 std::max<int>(1, own_.size()));
  // Filtered: between pixels, or between the colours of the four nearest Bayer cells; a mosaic's
  // pixels are gathered unfiltered, the shader interpolates its demosaic.
  const GLint filter = kind == ImageTexture::kMosaic ? GL_NEAREST : GL_LINEAR;
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  image_texture_ = kind;
}

void LumigraphRenderer::uploadImage(int own_index, int width, int height, const uint8_t* texels) {
  const bool mosaic = image_texture_ == ImageTexture::kMosaic;
  const size_t bytes = size_t(width) * height * (mosaic ? 1 : 4);
  glBindBuffer(GL_PIXEL_UNPACK_BUFFER, upload_buffer_);
  glBufferData(GL_PIXEL_UNPACK_BUFFER, GLsizeiptr(bytes), texels, GL_STREAM_DRAW);
  glBindTexture(GL_TEXTURE_2D_ARRAY, images_);
  glPixelStorei(GL_UNPACK_ALIGNMENT, mosaic ? 1 : 4);
  glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, own_index, width, height, 1,
                  mosaic ? GL_RED : GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
  glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
}

void LumigraphRenderer::setActive(const std::vector<bool>& active) {
  for (int c = 0; c < rig_.cameraCount(); ++c)
    active_[c] = c < static_cast<int>(active.size()) ? int(active[c]) : 1;
}

void LumigraphRenderer::render(const Camera& desired, std::vector<uint8_t>& rgba) {
  const Eigen::Affine3f identity = Eigen::Affine3f::Identity();
  render(desired, std::span<const Eigen::Affine3f>(&identity, 1), rgba);
}

void LumigraphRenderer::render(const Camera& desired, std::span<const Eigen::Affine3f> clones,
                               std::vector<uint8_t>& rgba) {
  target_.bind(desired.width(), desired.height(), "LumigraphRenderer");
  glClearColor(0, 0, 0, 0);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_BLEND);
  // Closed surfaces, counter-clockwise from outside: back faces are never seen (half the
  // fragments llvmpipe would otherwise shade before the front hides them).
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  glFrontFace(GL_CW);  // image rows go down the framebuffer: counter-clockwise turns clockwise

  const bool mosaic = image_texture_ == ImageTexture::kMosaic;
  const ShaderProgram& p = mosaic ? *programs_->mosaic : programs_->blend;
  p.use();
  const int n = rig_.cameraCount();
  Eigen::Matrix<float, 9, kMaxCameras> rotations;
  Eigen::Matrix<float, 3, kMaxCameras> translations, centres, radials;
  Eigen::Matrix<float, 4, kMaxCameras> focal_centres;
  Eigen::Matrix<float, 2, kMaxCameras> tangentials, sizes;
  float skews[kMaxCameras];
  for (int c = 0; c < n; ++c) {
    const CameraUniforms u = uniformsOf(rig_.camera(c));
    rotations.col(c) = Eigen::Map<const Eigen::Matrix<float, 9, 1>>(u.rotation.data());
    translations.col(c) = u.translation;
    centres.col(c) = u.centre;
    radials.col(c) = u.radial;
    focal_centres.col(c) = Eigen::Map<const Eigen::Vector4f>(u.focal_centre);
    tangentials.col(c) = Eigen::Vector2f(u.tangential[0], u.tangential[1]);
    sizes.col(c) = Eigen::Vector2f(u.size[0], u.size[1]);
    skews[c] = u.skew;
  }
  glUniformMatrix3fv(p.uniform("rotations"), n, GL_FALSE, rotations.data());
  glUniform3fv(p.uniform("translations"), n, translations.data());
  glUniform4fv(p.uniform("focal_centres"), n, focal_centres.data());
  glUniform1fv(p.uniform("skews"), n, skews);
  glUniform3fv(p.uniform("radials"), n, radials.data());
  glUniform2fv(p.uniform("tangentials"), n, tangentials.data());
  glUniform2fv(p.uniform("image_sizes"), n, sizes.data());
  glUniform3fv(p.uniform("centres"), n, centres.data());
  glUniform1iv(p.uniform("camera_active"), n, active_.data());
  glUniform1i(p.uniform("k_nearest"), params_.k);
  glUniform1f(p.uniform("min_facing"), params_.min_facing);
  glUniform1f(p.uniform("max_angle"), params_.max_angle_rad);
  glUniform1f(p.uniform("epsilon"), params_.epsilon_rad);
  // A camera's pixel to its mask's texture coordinate: the mask's cells cover the camera's image.
  mask_scales_.resize(own_.size());
  for (size_t j = 0; j < own_.size(); ++j) {
    const Camera& camera = rig_.camera(own_[j]);
    const Eigen::Vector2i cells = j < mask_sizes_.size() ? mask_sizes_[j] : Eigen::Vector2i::Zero();
    mask_scales_[j] =
        cells.x() > 0 && mask_width_ > 0
            ? Eigen::Vector2f(float(cells.x()) / float(camera.width()) / float(mask_width_),
                              float(cells.y()) / float(camera.height()) / float(mask_height_))
            : Eigen::Vector2f::Zero();  // no mask: its layer reads "all in" everywhere
  }
  glUniform2fv(p.uniform("mask_scales"), GLsizei(own_.size()), mask_scales_[0].data());
  // Texel to texture coordinate: a Bayer cell's centre, at texel 2c + 1, is the centre of cell
  // texel c of the half-size array.
  if (mosaic) {
    glUniform2iv(p.uniform("mosaic_red"), GLsizei(own_.size()), mosaic_red_[0].data());
    glUniform2iv(p.uniform("mosaic_size"), GLsizei(own_.size()), mosaic_sizes_[0].data());
  }
  if (image_texture_ == ImageTexture::kCells) {
    glUniform2f(p.uniform("texel_scale"), 0.5f / float(std::max(1, images_width_ / 2)),
                0.5f / float(std::max(1, images_height_ / 2)));
  } else {
    glUniform2f(p.uniform("texel_scale"), 1.0f / float(images_width_),
                1.0f / float(images_height_));
  }
  glUniform1i(p.uniform("images"), 0);
  glUniform1i(p.uniform("masks"), 1);
  glUniform1i(p.uniform("use_masks"), masks_ ? 1 : 0);
  glUniform1f(p.uniform("misregistration_m"), params_.misregistration_m);
  glUniform1f(p.uniform("misregistration_noise"), params_.misregistration_noise);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D_ARRAY, images_);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D_ARRAY, masks_);
  glActiveTexture(GL_TEXTURE0);

  const CameraUniforms v = uniformsOf(desired);
  setDesiredCamera(p, v);
  glBindVertexArray(vao_);
  if (images_ && !own_.empty()) {
    for (const Eigen::Affine3f& clone : clones) {
      // The view-dependent weights in the clone's frame: the desired centre brought into the
      // captured actor's frame.
      const Eigen::Vector3f desired_in_actor = clone.inverse() * v.centre;
      const Eigen::Matrix4f m = clone.matrix();
      glUniformMatrix4fv(p.uniform("clone"), 1, GL_FALSE, m.data());
      glUniform3fv(p.uniform("desired_centre"), 1, desired_in_actor.data());
      // Each own camera's despill: by the angle between the rays from the mesh's centre to the
      // desired camera and to that camera.
      const Eigen::Vector3f to_desired = desired_in_actor - mesh_centre_;
      for (size_t j = 0; j < own_.size(); ++j) {
        const Eigen::Vector3f to_camera = centres.col(own_[j]) - mesh_centre_;
        const float angle =
            std::atan2(to_desired.cross(to_camera).norm(), to_desired.dot(to_camera));
        const float a = params_.despill_angle_rad;
        const float t = a > 0 ? std::clamp(angle / a, 0.0f, 1.0f) : 0.0f;
        despill_[j] = t * t * (3 - 2 * t);  // smoothstep(0, a, angle)
      }
      glUniform1fv(p.uniform("despill"), GLsizei(own_.size()), despill_.data());
      glDrawElements(GL_TRIANGLES, index_count_, GL_UNSIGNED_INT, nullptr);
    }
  }
  glBindVertexArray(0);
  glDisable(GL_CULL_FACE);

  target_.readRgba(rgba);
}

}  // namespace lumistage
