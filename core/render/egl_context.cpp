#include "core/render/egl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include "core/base/error.h"
#include "core/render/gl.h"

namespace lumistage {

namespace {

std::string eglErrorName(EGLint error) {
  switch (error) {
    case EGL_NOT_INITIALIZED:
      return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ALLOC:
      return "EGL_BAD_ALLOC";
    case EGL_BAD_CONFIG:
      return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT:
      return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY:
      return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH:
      return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER:
      return "EGL_BAD_PARAMETER";
    default:
      return "EGL error " + std::to_string(error);
  }
}

// Tries one display: initialise, bind OpenGL, create a 4.3 core context. Empty on success.
std::string tryDisplay(EGLDisplay display, EGLContext& context) {
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display, &major, &minor))
    return "eglInitialize: " + eglErrorName(eglGetError());
  if (!eglBindAPI(EGL_OPENGL_API)) return "no desktop OpenGL: " + eglErrorName(eglGetError());
  const EGLint config_attributes[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                      EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint count = 0;
  eglChooseConfig(display, config_attributes, &config, 1, &count);
  const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                       4,
                                       EGL_CONTEXT_MINOR_VERSION,
                                       3,
                                       EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                       EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                       EGL_NONE};
  context = eglCreateContext(display, count > 0 ? config : EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT,
                             context_attributes);
  if (context == EGL_NO_CONTEXT) {
    eglTerminate(display);
    return "no OpenGL 4.3 core context: " + eglErrorName(eglGetError());
  }
  if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
    eglDestroyContext(display, context);
    eglTerminate(display);
    return "eglMakeCurrent without a surface: " + eglErrorName(eglGetError());
  }
  return {};
}

}  // namespace

EglContext::EglContext() {
  auto query_devices =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  auto query_device_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
      eglGetProcAddress("eglQueryDeviceStringEXT"));
  auto platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  std::string tried;
  if (query_devices && platform_display) {
    EGLDeviceEXT devices[16];
    EGLint count = 0;
    query_devices(16, devices, &count);
    // Hardware devices first, Mesa's software device last.
    for (int pass = 0; pass < 2 && !context_; ++pass) {
      for (EGLint i = 0; i < count && !context_; ++i) {
        const char* extensions =
            query_device_string ? query_device_string(devices[i], EGL_EXTENSIONS) : nullptr;
        const bool software =
            extensions &&
            std::string(extensions).find("EGL_MESA_device_software") != std::string::npos;
        if (software != (pass == 1)) continue;
        EGLDisplay display = platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        if (display == EGL_NO_DISPLAY) continue;
        EGLContext context = EGL_NO_CONTEXT;
        const std::string error = tryDisplay(display, context);
        if (error.empty()) {
          display_ = display;
          context_ = context;
          software_ = software;
        } else {
          tried += "\n  EGL device " + std::to_string(i) + ": " + error;
        }
      }
    }
  } else {
    tried += "\n  EGL device enumeration (EGL_EXT_device_enumeration) is not available";
  }
  if (!context_) {
    EGLDisplay display = eglGetDisplay(EGL_DEFAULT_DISPLAY);
    EGLContext context = EGL_NO_CONTEXT;
    const std::string error =
        display == EGL_NO_DISPLAY ? "no default display" : tryDisplay(display, context);
    if (!error.empty()) {
      throw Error(
          "cannot create a headless OpenGL 4.3 context through EGL; tried:" + tried +
          "\n  default display: " + error +
          "\n(install Mesa's EGL and GL drivers: libegl-mesa0 libgl1-mesa-dri, or a GPU driver)");
    }
    display_ = display;
    context_ = context;
  }
  const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const char* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  description_ = std::string(renderer ? renderer : "?") + " / " + (version ? version : "?");
  software_ = software_ || currentRendererIsSoftware();
}

bool currentRendererIsSoftware() {
  const char* name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const std::string renderer = name ? name : "";
  return renderer.find("llvmpipe") != std::string::npos ||
         renderer.find("softpipe") != std::string::npos;
}

EglContext::~EglContext() {
  if (display_) {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (context_) eglDestroyContext(display_, context_);
    eglTerminate(display_);
  }
}

void EglContext::makeCurrent() {
  if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_)) {
    throw Error("eglMakeCurrent failed: " + eglErrorName(eglGetError()));
  }
}

}  // namespace lumistage
