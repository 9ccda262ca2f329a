#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "core/capture/image.h"
#include "core/geometry/rig.h"
#include "core/render/draw_order.h"
#include "core/render/gl.h"
#include "core/render/phong_subdivision.h"
#include "core/render/render_target.h"
#include "core/render/vertex_visibility.h"

namespace lumistage {

// How the lumigraph weighs and tests cameras (docs/lumigraph.md has the weight function).
struct LumigraphParams {
  int k = 4;                    // cameras blended per vertex (at most 4; docs/lumigraph.md)
  float min_facing = 0.1f;      // cos of 84 degrees: grazing views are left out
  float max_angle_rad = 1.57f;  // the threshold when at most k cameras qualify
  float epsilon_rad = 1e-4f;    // angles below this count as this
  // Visibility (VertexVisibility) from depth maps of the mesh rasterised by the CPU at the
  // cameras' size / this: 12 maps of 256x192 for the reference rig, about 2 ms. Not used when the
  // caller gives the masks (the studio computes them once a frame for every node).
  int depth_map_divisor = 4;
  float depth_tolerance_m = 0.03f;  // a vertex this far behind the map's surface is occluded
  // The flat triangles between vertices on a curved surface cut inside it: by the sagitta of an
  // edge at its middle, (its length)² x curvature / 8, about 3 mm for 3.5 cm edges on a 5 cm limb,
  // which left a one-pixel rim of the silhouette uncovered. The desired view rasterises each
  // vertex out along its normal by rim_dilation x the mean sagitta of its edges where the surface
  // is convex (texture coordinates and weights stay the vertex's); 0 turns it off. At 1 the edges'
  // middles reach the surface: a 42-vertex sphere's silhouette misses 0.7% of the true one's
  // pixels and draws 1.4% beyond it, against 7.5% missed unmoved. A finely tessellated mesh moves
  // by next to nothing.
  float rim_dilation = 1.0f;
  // Renders the mesh once subdivided as the curved surface through its vertices and normals
  // (PhongSubdivision: four times the triangles, the texture projected from the curved surface),
  // after its visibility is known; the rim dilation then follows the finer edges. Leave-one-out on
  // the refined generic human +0.2 dB over the actor's mask and +0.1 to +0.2 dB over the matte
  // (docs/lumigraph.md). Off for meshes finely tessellated already (the true surface).
  bool phong_subdivision = true;
  // Suppresses the screen's green spill in the colours of the cameras that look from elsewhere
  // than the desired camera, as keyers do: a camera's green at most the larger of its red and
  // blue, fully where the rays from the mesh's centre to the desired and to the input camera are
  // this far apart, not at all where they coincide (the spill a camera sees at its grazing angles
  // is its own view's: a desired camera on an input camera still gives that camera's image, spill
  // and all); 0: off. The screen's light on the actor's edges, and the screen itself where a camera
  // sees past a mesh a little too wide (between the legs), was blended into other views as green
  // fringes and patches. An actor on a green screen wears no green, which would key as the screen.
  // Leave-one-out +0.01 to +0.07 dB over the actor's mask and the matte alike (docs/lumigraph.md).
  float despill_angle_rad = 0.17f;
  // Where the mesh misses the actor's surface by a few millimetres, a camera's texture slides
  // across the view by as much as that error moves the point in the camera's image: nothing on
  // uniform cloth, a whole stripe's edge where the image changes fast along that direction. Each
  // own camera's weight is therefore divided, per fragment, by 1 + e² / misregistration_noise²,
  // with e² the mean squared colour difference (RGB, 0..1) between its texel and the texels to
  // either side of it by the shift that moving the point misregistration_m along the desired ray
  // gives in its image (at most 4 pixels): the camera's expected error were the surface that far
  // off, as it would show in this view. Where the image is flat every camera keeps its weight;
  // across the shirt's horizontal stripes the cameras at the other height, whose shift is
  // vertical, give way to those at the same height, whose shift runs along the stripes. A desired
  // camera on an input camera shifts that camera's texel by nothing: its image still. The refined
  // generic human lies 3 mm from the actor on average; the noise, 6.4 levels, is about the sensor
  // noise's contribution to e². 0: off. Leave-one-camera-out on the four reference clips +0.26 dB
  // over the actor's mask (docs/lumigraph.md). A node's share (alpha) is then the own cameras'
  // weight so divided over the rig's undivided total, so the nodes' shares no longer sum to one,
  // and the studio's per-pixel normalisation weighs them.
  float misregistration_m = 0.006f;
  float misregistration_noise = 0.025f;
  // How Bayer images reach the shader: as their 2x2 cells' colours (R, the mean of the two G, B:
  // half the camera's resolution each way), or at full resolution: the mosaic uploaded as it is
  // and demosaiced in the fragment shader (bilinearly, as OpenCV's demosaic with which `lumistage
  // eval` shows a camera's image; four gathers a camera and fragment instead of one filtered
  // read). Either uploads one byte a pixel. Full resolution: leave-one-camera-out on Bayer
  // sessions of the four reference clips +0.38 dB over the actor's mask (the true surface 27.7 ->
  // 28.6 dB). On an H200 a node's 640x480 view costs 0.19 ms against 0.18 ms, its three images
  // upload in 0.55 ms either way; on Mesa llvmpipe the view costs 1.6 ms more CPU, which four
  // nodes and the studio sharing the CPU cannot spare (docs/lumigraph.md). kAuto: full resolution
  // on a GPU, cells on a software renderer.
  enum class BayerImages { kAuto, kCells, kFullResolution };
  BayerImages bayer_images = BayerImages::kAuto;
};

// Unstructured lumigraph rendering on the GPU (or Mesa llvmpipe), through an offscreen OpenGL 4.3
// context that must be current for the renderer's whole life (EglContext). Takes any triangle
// mesh with per-vertex normals (the truth surface, the posed generic human, the refined mesh),
// the rig, and the images of `own` cameras (a node's; all of them for the single-process
// renderer). Weights are computed per vertex over *every* active camera of the rig, with
// visibility per vertex and camera (VertexVisibility, from small depth maps of the mesh), so that
// renderers that own different cameras agree on them. A render writes RGBA8 (rows top first):
// colour = weighted mean of the own cameras' images (each camera's weight divided by its
// misregistration there, LumigraphParams), alpha = the own cameras' so divided weight's share of
// the rig's undivided total, on a log scale (shareOfAlpha, partial_image_blender.h; 0 where no
// camera sees the surface). Blending the partial images of all nodes (PartialImageBlender) gives
// the single-process image.
class LumigraphRenderer {
 public:
  static constexpr int kMaxCameras = VertexVisibility::kMaxCameras;

  // Throws Error for more than kMaxCameras cameras, an own index out of the rig, or GL failures.
  LumigraphRenderer(const Rig& rig, std::vector<int> own, LumigraphParams params = {});
  ~LumigraphRenderer();
  LumigraphRenderer(const LumigraphRenderer&) = delete;
  LumigraphRenderer& operator=(const LumigraphRenderer&) = delete;

  const std::vector<int>& ownCameras() const { return own_; }
  const LumigraphParams& params() const { return params_; }

  // The surface for the next renders (in the capture's frame), with which cameras see each
  // vertex: given, one mask a vertex, bit c for rig camera c, as VertexVisibility computes them
  // (the studio sends the nodes these), or, when none are given, computed here (VertexVisibility
  // at params().depth_map_divisor). `normals` unit, outward. Allocates only when the mesh grows.
  // Throws Error for masks of another vertex count.
  void setMesh(const Eigen::Matrix3Xf& positions, const Eigen::Matrix3Xf& normals,
               std::span<const Eigen::Vector3i> triangles,
               std::span<const CameraMask> visibility = {});
  // The image of own camera `own_index` (index into ownCameras()). Bayer images upload their
  // 2x2 cells' colours (R, the mean of the two G, B; as many bytes as the Bayer image), which the
  // shader samples bilinearly, or, with params().bayer_images kFullResolution, the mosaic itself,
  // which the shader demosaics. rgb8 is widened to RGBA, mono8 to grey RGBA. All own images must
  // share one kind, Bayer or not (a renderer's are one session's or one node's cameras); the
  // Bayer layouts may differ.
  void setImage(int own_index, const ImageView& image);
  // RGBA8 (rows top first) as setImage(rgb8) would take it.
  void setImageRgba(int own_index, const uint8_t* rgba, int width, int height);
  // Cameras that take part in the weights (default: all). Leave-one-out renders a camera's view
  // with that camera inactive.
  void setActive(const std::vector<bool>& active);
  // A low-resolution foreground mask of own camera `own_index`'s current image (one byte a cell,
  // 0 background, 255 foreground; its cells cover the camera's image, cameras of any sizes). A
  // camera's weight is scaled by the mask (bilinear) where it samples: where the
  // mesh reaches beyond the actor in that camera, the others colour it; just beyond it in all, the
  // cameras' colours weighted by their masks, at a sixteenth of the share; further beyond it in
  // all, nothing (the fragment is discarded, and what lies behind it shows). Without masks, every
  // pixel counts.
  void setMask(int own_index, std::span<const uint8_t> mask, int width, int height);

  // Renders the desired camera's view (its size, lens distortion included) of every clone: a
  // rigid placement of the captured actor, stage (world) from the capture's frame, the identity
  // being the actor where it was filmed (CloneSet::transforms() gives them). One draw each; an
  // empty set renders nothing. `rgba` is resized when its size differs.
  void render(const Camera& desired, std::span<const Eigen::Affine3f> clones,
              std::vector<uint8_t>& rgba);
  // The actor where it was filmed.
  void render(const Camera& desired, std::vector<uint8_t>& rgba);

 private:
  // What the cameras' texture array holds: RGBA8 images of the cameras' size, their Bayer cells'
  // colours (RGBA8, half the size), or their Bayer mosaics (R8, the cameras' size).
  enum class ImageTexture { kRgba, kCells, kMosaic };
  // The array for `kind`, remade on a change.
  void useImageFormat(ImageTexture kind);
  // The mesh's vertices (with their rim dilations), triangles and masks into the GL buffers.
  void upload(const Eigen::Matrix3Xf& positions, const Eigen::Matrix3Xf& normals,
              std::span<const Eigen::Vector3i> triangles, std::span<const CameraMask> visibility);
  // width x height texels (RGBA, or one byte for a mosaic) into the array's layer `own_index`,
  // through the pixel-buffer object.
  void uploadImage(int own_index, int width, int height, const uint8_t* texels);

  struct Programs;
  std::unique_ptr<Programs> programs_;
  Rig rig_;
  std::vector<int> own_;
  LumigraphParams params_;
  std::vector<int> active_;
  GLuint vao_ = 0, vertex_buffer_ = 0, index_buffer_ = 0;
  GLsizei index_count_ = 0;
  GLsizeiptr vertex_capacity_ = 0, index_capacity_ = 0;
  GLuint images_ = 0;  // 2D array texture, one layer per own camera
  GLuint masks_ = 0;   // 2D array texture of the own cameras' foreground masks, once given
  int mask_width_ = 0, mask_height_ = 0;  // the array's layers: the largest mask given
  // Each own camera's mask, in the corner of its layer: its cells (0: none, all in), and the
  // scale from the camera's pixels to the array's texture coordinate (for the shader).
  std::vector<Eigen::Vector2i> mask_sizes_;
  std::vector<Eigen::Vector2f> mask_scales_;
  int images_width_ = 0, images_height_ = 0;
  ImageTexture image_texture_ = ImageTexture::kRgba;
  // Per own camera, for a mosaic: where R sits in its 2x2 cell, and its image's size.
  std::vector<Eigen::Vector2i> mosaic_red_, mosaic_sizes_;
  GLuint visibility_buffer_ = 0;  // one 32-bit camera mask a vertex (vertex attribute 3)
  GLsizeiptr visibility_capacity_ = 0;
  VertexVisibility visibility_;
  PhongSubdivision subdivision_;
  DrawOrder draw_order_;  // the uploaded mesh's, and its masks in that order
  std::vector<CameraMask> ordered_visibility_;
  RenderTarget target_;
  GLuint upload_buffer_ = 0;      // pixel-buffer object for image uploads
  std::vector<float> vertices_;   // interleaved positions, normals and rim dilations, reused
  std::vector<uint8_t> staging_;  // an image's texels on their way up, reused
  Eigen::Vector3f mesh_centre_ = Eigen::Vector3f::Zero();  // the uploaded vertices' mean
  std::vector<float>
      despill_;  // per own camera, for the shader (LumigraphParams::despill_angle_rad)
  std::vector<float> rim_sum_;  // per vertex: the sagittas of its edges, and their count
  std::vector<int> rim_count_;
};

}  // namespace lumistage
