#pragma once
// GLSL programs built from the shaders/ sources embedded at build time. Every stage gets
// shaders/common.glsl (the per-frame uniform block, lighting, fog, gamma) prepended after the
// #version line.

#include <initializer_list>
#include <string>
#include <string_view>

#include "common/status.h"
#include "render/gl_api.h"

namespace gk {

// Source of an embedded shader by file name ("skinned.vert"); empty if there is none.
std::string_view embedded_shader(std::string_view name);

// Source by file name: from $GAITKEEPER_SHADER_DIR when that variable is set (live editing without
// a rebuild), else the embedded copy. Errors name the file.
Result<std::string> load_shader_source(std::string_view name);

// A linked program; owns the GL object. Needs a current context for creation and destruction.
class ShaderProgram {
 public:
  ShaderProgram() = default;
  ~ShaderProgram();
  ShaderProgram(ShaderProgram&& other) noexcept;
  ShaderProgram& operator=(ShaderProgram&& other) noexcept;
  ShaderProgram(const ShaderProgram&) = delete;
  ShaderProgram& operator=(const ShaderProgram&) = delete;

  // Compiles vertex_file and fragment_file (each after common.glsl) and links them. Compile and
  // link errors carry the file names and the driver's info log.
  static Result<ShaderProgram> build(std::string_view vertex_file, std::string_view fragment_file);
  // Same from explicit source text (used by tests to check error reporting).
  static Result<ShaderProgram> build_from_source(std::string_view vertex_name,
                                                 std::string_view vertex_source,
                                                 std::string_view fragment_name,
                                                 std::string_view fragment_source);

  GLuint id() const { return id_; }
  // -1 when the uniform does not exist or was optimised out (glUniform ignores -1).
  GLint uniform(const char* name) const { return glGetUniformLocation(id_, name); }

 private:
  explicit ShaderProgram(GLuint id) : id_(id) {}
  GLuint id_ = 0;
};

}  // namespace gk
