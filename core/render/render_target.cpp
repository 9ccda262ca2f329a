#include "core/render/render_target.h"

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
