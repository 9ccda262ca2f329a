#pragma once

#include <string>

namespace lumistage {

// A headless OpenGL 4.3+ core context through EGL: no window, no display server. Picks a GPU
// when there is one (NVIDIA, Mesa hardware drivers) and otherwise Mesa's software renderer
// (llvmpipe), so the same code renders on a studio PC and on a CPU-only build machine.
// Rendering goes to framebuffer objects; the context has no default framebuffer.
class EglContext {
 public:
  // Creates the context and makes it current on this thread. Throws Error saying what was tried
  // and why each failed.
  EglContext();
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  void makeCurrent();
  // "NVIDIA H100 ... / 4.6.0 NVIDIA ..." or "llvmpipe (LLVM 15.0.6, 256 bits) / 4.5 (Core Profile)
  // Mesa".
  const std::string& description() const { return description_; }
  bool isSoftware() const { return software_; }

 private:
  void* display_ = nullptr;
  void* context_ = nullptr;
  std::string description_;
  bool software_ = false;
};

// Whether the OpenGL context current on this thread renders in software (Mesa llvmpipe or
// softpipe), from its GL_RENDERER.
bool currentRendererIsSoftware();

}  // namespace lumistage
