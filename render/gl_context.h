#pragma once
// An OpenGL 3.3+ core context and the framebuffer the renderer draws into:
//  - a GLFW window (X11/Wayland; needs a display), or
//  - offscreen through EGL (Mesa's surfaceless platform, else an EGL device, else the default
//    display with a pbuffer) rendering into an FBO; needs no display at all.
// Failures (no display, no EGL, GL too old) come back as a Status with the reason, never a crash.

#include <memory>
#include <string>

#include <glm/vec2.hpp>

#include "common/status.h"
#include "render/gl_api.h"

struct GLFWwindow;

namespace gk {

struct ContextOptions {
  int width = 1280;     // framebuffer width [px] [Limit: 1..16384]
  int height = 720;     // framebuffer height [px] [Limit: 1..16384]
  int samples = 0;      // MSAA samples, 0 = off [Limit: 0..16]
  bool visible = true;  // window only: false creates a hidden window
  bool vsync = true;    // window only
  std::string title = "Gaitkeeper";
};

class GlContext {
 public:
  static Result<std::unique_ptr<GlContext>> create_offscreen(const ContextOptions& options);
  static Result<std::unique_ptr<GlContext>> create_window(const ContextOptions& options);
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  bool is_offscreen() const { return window_ == nullptr; }
  // Current drawable size [px]: the window's framebuffer (which follows resizes and HiDPI) or the
  // fixed offscreen size.
  glm::ivec2 framebuffer_size() const;
  void make_current();
  // Binds the framebuffer to draw the frame into and sets the viewport to its size.
  void begin_frame();
  // Makes the frame readable by capture (resolves MSAA) and binds it as GL_READ_FRAMEBUFFER.
  // For a window this reads the back buffer, so capture before present().
  void finish_frame();
  // Window: swaps buffers. Offscreen: nothing.
  void present();

  GLFWwindow* window() const { return window_; }  // null offscreen (for ImGui / input)
  bool should_close() const;
  void poll_events();
  const std::string& description() const { return description_; }  // "4.5 (Core Profile) ..."

 private:
  GlContext() = default;
  Status create_framebuffers(int width, int height, int samples);
  Status check_gl_version();

  GLFWwindow* window_ = nullptr;
  void* egl_display_ = nullptr;  // EGLDisplay / EGLContext / EGLSurface kept opaque so the
  void* egl_context_ = nullptr;  // EGL headers (and their X11 defines) stay out of this header
  void* egl_surface_ = nullptr;
  glm::ivec2 size_{0, 0};
  int samples_ = 0;
  GLuint draw_fbo_ = 0;     // offscreen target (multisampled when samples_ > 0)
  GLuint resolve_fbo_ = 0;  // single-sample copy read by capture; equals draw_fbo_ without MSAA
  GLuint renderbuffers_[3] = {0, 0, 0};
  std::string description_;
};

}  // namespace gk
