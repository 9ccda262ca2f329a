#include "core/render/render_target.h"

#include <fmt/format.h>

#include <string>

#include "core/base/error.h"

namespace lumistage {

RenderTarget::~RenderTarget() {
  glDeleteFramebuffers(1, &framebuffer_);
  glDeleteRenderbuffers(1, &colour_);
  glDeleteRenderbuffers(1, &depth_);
}

void RenderTarget::bind(int width, int height, const char* owner) {
  if (width != width_ || height != height_) {
    GLint largest = 0;
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &largest);
    if (width <= 0 || height <= 0 || width > largest || height > largest) {
      throw Error(std::string(owner) + ": a view of " + std::to_string(width) + "x" +
                  std::to_string(height) + " pixels: this OpenGL device draws 1 to " +
                  std::to_string(largest) + " a side");
    }
    while (glGetError() != GL_NO_ERROR) {
    }  // earlier errors are not this allocation's
    if (!framebuffer_) {
      glGenFramebuffers(1, &framebuffer_);
      glGenRenderbuffers(1, &colour_);
      glGenRenderbuffers(1, &depth_);
    }
    glBindRenderbuffer(GL_RENDERBUFFER, colour_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
    glBindRenderbuffer(GL_RENDERBUFFER, depth_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width, height);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, colour_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_);
    // Storage refused (out of memory) keeps the old storage attached, complete at the old size:
    // reading the new size back would read beyond it.
    if (const GLenum error = glGetError(); error != GL_NO_ERROR) {
      width_ = height_ = 0;  // the next bind allocates again
      throw Error(std::string(owner) + ": cannot allocate a view of " + std::to_string(width) +
                  "x" + std::to_string(height) + " pixels (OpenGL error 0x" +
                  fmt::format("{:x}", error) +
                  (error == GL_OUT_OF_MEMORY ? ": out of memory)" : ")"));
    }
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      throw Error(std::string(owner) + ": framebuffer of " + std::to_string(width) + "x" +
                  std::to_string(height) + " is incomplete");
    }
    width_ = width;
    height_ = height;
  }
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
  glViewport(0, 0, width_, height_);
}

void RenderTarget::readRgba(std::vector<uint8_t>& rgba) const {
  const size_t bytes = size_t(width_) * height_ * 4;
  if (rgba.size() != bytes) rgba.resize(bytes);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
}

}  // namespace lumistage
