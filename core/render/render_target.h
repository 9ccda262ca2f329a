#pragma once

#include <cstdint>
#include <vector>

#include "core/render/gl.h"

namespace lumistage {

// An offscreen RGBA8 colour + 24-bit depth framebuffer whose size may change between frames
// (storage is reallocated only on a change). Owns its GL objects: create, use and destroy it with
// the same OpenGL context current.
class RenderTarget {
 public:
  RenderTarget() = default;
  ~RenderTarget();
  RenderTarget(const RenderTarget&) = delete;
  RenderTarget& operator=(const RenderTarget&) = delete;

  // Makes it width x height, binds it as the framebuffer and sets the viewport to it. Throws Error
  // naming `owner` when the driver refuses the framebuffer.
  void bind(int width, int height, const char* owner);
  // Reads the colour back: RGBA, rows bottom-up as OpenGL gives them; `rgba` is resized only when
  // its size differs.
  void readRgba(std::vector<uint8_t>& rgba) const;

  int width() const { return width_; }
  int height() const { return height_; }

 private:
  GLuint framebuffer_ = 0, colour_ = 0, depth_ = 0;
  int width_ = 0, height_ = 0;
};

}  // namespace lumistage
