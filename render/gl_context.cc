#include "render/gl_context.h"

#include <cstdio>
#include <cstring>
#include <string>

// Keep X11's macros (None, Status, ...) out: they clash with gk::Status.
#define EGL_NO_X11
#define MESA_EGL_NO_X11_HEADERS
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GLFW/glfw3.h>

namespace gk {
namespace {

// EGL displays and GLFW are process-wide; reference counts let several contexts coexist (tests
// create one per fixture) without one teardown pulling the rug from under another.
int g_egl_users = 0;
int g_glfw_users = 0;
std::string g_glfw_error;

void on_glfw_error(int code, const char* description) {
  g_glfw_error = "GLFW error " + std::to_string(code) + ": " + (description ? description : "?");
}

bool has_extension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const size_t n = std::strlen(name);
  for (const char* p = std::strstr(list, name); p != nullptr; p = std::strstr(p + n, name)) {
    const bool starts = p == list || p[-1] == ' ';
    const bool ends = p[n] == '\0' || p[n] == ' ';
    if (starts && ends) return true;
  }
  return false;
}

std::string egl_error_text() {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "EGL error 0x%04X", eglGetError());
  return buffer;
}

// Tries the displays that need no window system, best first; returns EGL_NO_DISPLAY and a reason
// for each attempt when none initialises.
EGLDisplay open_headless_display(std::string* out_reasons) {
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  auto try_init = [&](EGLDisplay display, const char* what) {
    if (display == EGL_NO_DISPLAY) {
      *out_reasons += std::string(what) + ": no display; ";
      return false;
    }
    EGLint major = 0, minor = 0;
    if (eglInitialize(display, &major, &minor) != EGL_TRUE) {
      *out_reasons += std::string(what) + ": eglInitialize failed (" + egl_error_text() + "); ";
      return false;
    }
    return true;
  };
  if (get_platform_display != nullptr && has_extension(client, "EGL_MESA_platform_surfaceless")) {
    EGLDisplay d =
        get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (try_init(d, "surfaceless")) return d;
  }
  if (get_platform_display != nullptr && has_extension(client, "EGL_EXT_platform_device")) {
    auto query_devices =
        reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    EGLDeviceEXT devices[8];
    EGLint num_devices = 0;
    if (query_devices != nullptr && query_devices(8, devices, &num_devices) == EGL_TRUE) {
      for (EGLint i = 0; i < num_devices; ++i) {
        EGLDisplay d = get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        if (try_init(d, "EGL device")) return d;
      }
    }
  }
  EGLDisplay d = eglGetDisplay(EGL_DEFAULT_DISPLAY);
  if (try_init(d, "default display")) return d;
  return EGL_NO_DISPLAY;
}

}  // namespace

Result<std::unique_ptr<GlContext>> GlContext::create_offscreen(const ContextOptions& options) {
  if (options.width < 1 || options.height < 1 || options.width > 16384 || options.height > 16384) {
    return Status::Error("offscreen context: bad size " + std::to_string(options.width) + "x" +
                         std::to_string(options.height) + " (expected 1..16384 each)");
  }
  std::string reasons;
  EGLDisplay display = open_headless_display(&reasons);
  if (display == EGL_NO_DISPLAY) {
    return Status::Error("offscreen context: no usable EGL display (" + reasons +
                         "install libegl-mesa0 and libgl1-mesa-dri)");
  }
  std::unique_ptr<GlContext> ctx(new GlContext());
  ++g_egl_users;  // from here the destructor owns the display reference
  ctx->egl_display_ = display;
  if (eglBindAPI(EGL_OPENGL_API) != EGL_TRUE) {
    return Status::Error("offscreen context: EGL cannot bind desktop OpenGL (" + egl_error_text() +
                         ")");
  }
  const char* display_ext = eglQueryString(display, EGL_EXTENSIONS);
  const bool configless = has_extension(display_ext, "EGL_KHR_no_config_context") ||
                          has_extension(display_ext, "EGL_MESA_configless_context");
  const bool surfaceless = has_extension(display_ext, "EGL_KHR_surfaceless_context");
  EGLConfig config = nullptr;  // EGL_NO_CONFIG_KHR
  if (!configless || !surfaceless) {
    // Fallback for EGLs without surfaceless contexts: a tiny pbuffer just to make it current;
    // the frame itself always goes to our FBO.
    const EGLint config_attribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                     EGL_OPENGL_BIT, EGL_NONE};
    EGLint num_configs = 0;
    if (eglChooseConfig(display, config_attribs, &config, 1, &num_configs) != EGL_TRUE ||
        num_configs < 1) {
      return Status::Error("offscreen context: no EGL config with pbuffer + OpenGL support");
    }
    const EGLint pbuffer_attribs[] = {EGL_WIDTH, 16, EGL_HEIGHT, 16, EGL_NONE};
    ctx->egl_surface_ = eglCreatePbufferSurface(display, config, pbuffer_attribs);
    if (ctx->egl_surface_ == EGL_NO_SURFACE) {
      return Status::Error("offscreen context: eglCreatePbufferSurface failed (" +
                           egl_error_text() + ")");
    }
  }
  const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                    3,
                                    EGL_CONTEXT_MINOR_VERSION,
                                    3,
                                    EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                    EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                    EGL_NONE};
  ctx->egl_context_ = eglCreateContext(display, config, EGL_NO_CONTEXT, context_attribs);
  if (ctx->egl_context_ == EGL_NO_CONTEXT) {
    return Status::Error("offscreen context: cannot create an OpenGL 3.3 core context (" +
                         egl_error_text() + ")");
  }
  ctx->make_current();
  if (eglGetCurrentContext() != ctx->egl_context_) {
    return Status::Error("offscreen context: eglMakeCurrent failed (" + egl_error_text() + ")");
  }
  GK_RETURN_IF_ERROR(ctx->check_gl_version());
  GK_RETURN_IF_ERROR(ctx->create_framebuffers(options.width, options.height, options.samples));
  return ctx;
}

Result<std::unique_ptr<GlContext>> GlContext::create_window(const ContextOptions& options) {
  if (options.width < 1 || options.height < 1 || options.width > 16384 || options.height > 16384) {
    return Status::Error("window: bad size " + std::to_string(options.width) + "x" +
                         std::to_string(options.height) + " (expected 1..16384 each)");
  }
  glfwSetErrorCallback(on_glfw_error);
  g_glfw_error.clear();
  if (glfwInit() != GLFW_TRUE) {
    return Status::Error("window: cannot initialise GLFW (no display? DISPLAY/WAYLAND_DISPLAY " +
                         std::string("unset or unreachable; use offscreen mode or xvfb-run): ") +
                         g_glfw_error);
  }
  std::unique_ptr<GlContext> ctx(new GlContext());
  ++g_glfw_users;  // from here the destructor balances glfwInit
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_SAMPLES, options.samples);
  glfwWindowHint(GLFW_VISIBLE, options.visible ? GLFW_TRUE : GLFW_FALSE);
  ctx->window_ =
      glfwCreateWindow(options.width, options.height, options.title.c_str(), nullptr, nullptr);
  if (ctx->window_ == nullptr) {
    return Status::Error("window: cannot create an OpenGL 3.3 core window: " + g_glfw_error);
  }
  ctx->make_current();
  glfwSwapInterval(options.vsync ? 1 : 0);
  GK_RETURN_IF_ERROR(ctx->check_gl_version());
  ctx->samples_ = options.samples;
  return ctx;
}

GlContext::~GlContext() {
  if (draw_fbo_ != 0 || resolve_fbo_ != 0) {
    make_current();
    if (resolve_fbo_ != 0 && resolve_fbo_ != draw_fbo_) glDeleteFramebuffers(1, &resolve_fbo_);
    if (draw_fbo_ != 0) glDeleteFramebuffers(1, &draw_fbo_);
    glDeleteRenderbuffers(3, renderbuffers_);
  }
  if (window_ != nullptr) glfwDestroyWindow(window_);
  if (egl_display_ != nullptr) {
    eglMakeCurrent(egl_display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (egl_surface_ != nullptr) eglDestroySurface(egl_display_, egl_surface_);
    if (egl_context_ != nullptr) eglDestroyContext(egl_display_, egl_context_);
    if (--g_egl_users == 0) {
      eglTerminate(egl_display_);
      eglReleaseThread();
    }
  } else if (--g_glfw_users == 0) {  // only windows hold a GLFW reference
    glfwTerminate();
  }
}

Status GlContext::check_gl_version() {
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  const char* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  description_ = std::string(version ? version : "?") + " on " + (renderer ? renderer : "?");
  if (major * 10 + minor < 33) {
    return Status::Error("OpenGL 3.3 core required, got " + description_);
  }
  return Status::Ok();
}

Status GlContext::create_framebuffers(int width, int height, int samples) {
  GLint max_samples = 0;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  if (samples < 0 || samples > max_samples) {
    return Status::Error("offscreen context: " + std::to_string(samples) +
                         " MSAA samples requested, the driver allows 0.." +
                         std::to_string(max_samples));
  }
  size_ = {width, height};
  samples_ = samples;
  glGenRenderbuffers(3, renderbuffers_);
  glGenFramebuffers(1, &draw_fbo_);
  glBindFramebuffer(GL_FRAMEBUFFER, draw_fbo_);
  glBindRenderbuffer(GL_RENDERBUFFER, renderbuffers_[0]);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA8, width, height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                            renderbuffers_[0]);
  glBindRenderbuffer(GL_RENDERBUFFER, renderbuffers_[1]);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH24_STENCIL8, width, height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER,
                            renderbuffers_[1]);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
    return Status::Error("offscreen context: framebuffer incomplete at " + std::to_string(width) +
                         "x" + std::to_string(height));
  }
  resolve_fbo_ = draw_fbo_;
  if (samples > 0) {
    glGenFramebuffers(1, &resolve_fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo_);
    glBindRenderbuffer(GL_RENDERBUFFER, renderbuffers_[2]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                              renderbuffers_[2]);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      return Status::Error("offscreen context: resolve framebuffer incomplete");
    }
  }
  glBindFramebuffer(GL_FRAMEBUFFER, draw_fbo_);
  return Status::Ok();
}

glm::ivec2 GlContext::framebuffer_size() const {
  if (window_ == nullptr) return size_;
  glm::ivec2 size;
  glfwGetFramebufferSize(window_, &size.x, &size.y);
  return size;
}

void GlContext::make_current() {
  if (window_ != nullptr) {
    glfwMakeContextCurrent(window_);
  } else if (egl_display_ != nullptr) {
    eglMakeCurrent(egl_display_, egl_surface_, egl_surface_, egl_context_);
  }
}

void GlContext::begin_frame() {
  glBindFramebuffer(GL_FRAMEBUFFER, window_ != nullptr ? 0 : draw_fbo_);
  const glm::ivec2 size = framebuffer_size();
  glViewport(0, 0, size.x, size.y);
}

void GlContext::finish_frame() {
  const glm::ivec2 size = framebuffer_size();
  if (window_ == nullptr && resolve_fbo_ != draw_fbo_) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, draw_fbo_);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, resolve_fbo_);
    glBlitFramebuffer(0, 0, size.x, size.y, 0, 0, size.x, size.y, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  }
  glBindFramebuffer(GL_READ_FRAMEBUFFER, window_ != nullptr ? 0 : resolve_fbo_);
  if (window_ != nullptr) glReadBuffer(GL_BACK);
}

void GlContext::present() {
  if (window_ != nullptr) glfwSwapBuffers(window_);
}

bool GlContext::should_close() const {
  return window_ != nullptr && glfwWindowShouldClose(window_) == GLFW_TRUE;
}

void GlContext::poll_events() {
  if (window_ != nullptr) glfwPollEvents();
}

}  // namespace gk
