#include "render/shader_program.h"

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace gk {
namespace {

// GLSL 3.30 core is the floor: it has everything we use (texture buffers, integer attributes,
// instancing) and Mesa, macOS-era drivers and every desktop GPU since 2010 provide it.
constexpr std::string_view kVersionLine = "#version 330 core\n";
constexpr std::string_view kCommonFile = "common.glsl";

std::string info_log(GLuint object, bool is_program) {
  GLint length = 0;
  if (is_program) {
    glGetProgramiv(object, GL_INFO_LOG_LENGTH, &length);
  } else {
    glGetShaderiv(object, GL_INFO_LOG_LENGTH, &length);
  }
  std::string log(static_cast<size_t>(length > 0 ? length : 1), '\0');
  if (is_program) {
    glGetProgramInfoLog(object, length, nullptr, log.data());
  } else {
    glGetShaderInfoLog(object, length, nullptr, log.data());
  }
  while (!log.empty() && (log.back() == '\0' || log.back() == '\n')) log.pop_back();
  return log;
}

// Compiles chunks concatenated in order. The driver numbers lines per chunk ("0:12" = chunk 0,
// line 12), so the error lists the chunk names in order to make that readable.
Result<GLuint> compile(
    GLenum stage, std::initializer_list<std::pair<std::string_view, std::string_view>> chunks) {
  std::vector<const GLchar*> texts;
  std::vector<GLint> lengths;
  std::string names;
  int index = 0;
  for (const auto& [name, text] : chunks) {
    texts.push_back(text.data());
    lengths.push_back(static_cast<GLint>(text.size()));
    if (!names.empty()) names += ", ";
    names += std::to_string(index++) + "=" + std::string(name);
  }
  GLuint shader = glCreateShader(stage);
  if (shader == 0) return Status::Error("glCreateShader failed (is a GL context current?)");
  glShaderSource(shader, static_cast<GLsizei>(texts.size()), texts.data(), lengths.data());
  glCompileShader(shader);
  GLint ok = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok != GL_TRUE) {
    std::string log = info_log(shader, false);
    glDeleteShader(shader);
    const char* kind = stage == GL_VERTEX_SHADER ? "vertex" : "fragment";
    return Status::Error(std::string(chunks.begin()[chunks.size() - 1].first) + ": " + kind +
                         " shader failed to compile (source chunks " + names + "):\n" + log);
  }
  return shader;
}

// Links two compiled stages (taking ownership of both, also on failure).
Result<GLuint> link(Result<GLuint> v, Result<GLuint> f, const std::string& label) {
  if (!v.ok() || !f.ok()) {
    if (v.ok()) glDeleteShader(*v);
    if (f.ok()) glDeleteShader(*f);
    return v.ok() ? f.status() : v.status();
  }
  GLuint program = glCreateProgram();
  glAttachShader(program, *v);
  glAttachShader(program, *f);
  glLinkProgram(program);
  glDeleteShader(*v);  // the program keeps them alive while attached
  glDeleteShader(*f);
  GLint ok = GL_FALSE;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (ok != GL_TRUE) {
    std::string log = info_log(program, true);
    glDeleteProgram(program);
    return Status::Error(label + ": program failed to link:\n" + log);
  }
  return program;
}

}  // namespace

Result<std::string> load_shader_source(std::string_view name) {
  if (const char* dir = std::getenv("GAITKEEPER_SHADER_DIR"); dir != nullptr && *dir != '\0') {
    const std::string path = std::string(dir) + "/" + std::string(name);
    std::ifstream in(path, std::ios::binary);
    if (!in) return Status::Error(path + ": cannot open shader (GAITKEEPER_SHADER_DIR is set)");
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
  }
  std::string_view text = embedded_shader(name);
  if (text.empty()) return Status::Error(std::string(name) + ": no such embedded shader");
  return std::string(text);
}

ShaderProgram::~ShaderProgram() {
  if (id_ != 0) glDeleteProgram(id_);
}

ShaderProgram::ShaderProgram(ShaderProgram&& other) noexcept : id_(std::exchange(other.id_, 0)) {}

ShaderProgram& ShaderProgram::operator=(ShaderProgram&& other) noexcept {
  if (this != &other) {
    if (id_ != 0) glDeleteProgram(id_);
    id_ = std::exchange(other.id_, 0);
  }
  return *this;
}

Result<ShaderProgram> ShaderProgram::build(std::string_view vertex_file,
                                           std::string_view fragment_file) {
  Result<std::string> common = load_shader_source(kCommonFile);
  GK_RETURN_IF_ERROR(common);
  Result<std::string> vs = load_shader_source(vertex_file);
  GK_RETURN_IF_ERROR(vs);
  Result<std::string> fs = load_shader_source(fragment_file);
  GK_RETURN_IF_ERROR(fs);
  Result<GLuint> v = compile(
      GL_VERTEX_SHADER, {{"version", kVersionLine}, {kCommonFile, *common}, {vertex_file, *vs}});
  Result<GLuint> f =
      compile(GL_FRAGMENT_SHADER,
              {{"version", kVersionLine}, {kCommonFile, *common}, {fragment_file, *fs}});
  Result<GLuint> program = link(std::move(v), std::move(f),
                                std::string(vertex_file) + " + " + std::string(fragment_file));
  GK_RETURN_IF_ERROR(program);
  return ShaderProgram(*program);
}

Result<ShaderProgram> ShaderProgram::build_from_source(std::string_view vertex_name,
                                                       std::string_view vertex_source,
                                                       std::string_view fragment_name,
                                                       std::string_view fragment_source) {
  Result<GLuint> v =
      compile(GL_VERTEX_SHADER, {{"version", kVersionLine}, {vertex_name, vertex_source}});
  Result<GLuint> f =
      compile(GL_FRAGMENT_SHADER, {{"version", kVersionLine}, {fragment_name, fragment_source}});
  Result<GLuint> program = link(std::move(v), std::move(f),
                                std::string(vertex_name) + " + " + std::string(fragment_name));
  GK_RETURN_IF_ERROR(program);
  return ShaderProgram(*program);
}

}  // namespace gk
