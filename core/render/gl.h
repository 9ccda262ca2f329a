#pragma once

// OpenGL 4.x core entry points. GLVND's libOpenGL exports every core function and dispatches to
// whichever context is current (EGL here), so no loader is needed.
#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1
#endif
#include <GL/glcorearb.h>
