#pragma once
// The one place that includes the OpenGL headers. GL_GLEXT_PROTOTYPES (set by CMake) declares every
// core entry point, which GLVND's libOpenGL exports and routes to the current GLX or EGL context.

#include <GL/glcorearb.h>
