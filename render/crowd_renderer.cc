#include "render/crowd_renderer.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <utility>

namespace gk {
namespace {

// The palette block an agent is skinned with: its own, or its index in draw() by default.
int64_t palette_block(const AgentDraw& a, size_t i) {
  return a.palette < 0 ? static_cast<int64_t>(i) : a.palette;
}

template <typename T>
void grow_to(std::vector<T>* v, size_t n) {
  if (v->size() < n) v->resize(std::max(n, v->size() + v->size() / 2));
}

}  // namespace

CrowdRenderer::CrowdRenderer() = default;

CrowdRenderer::~CrowdRenderer() { release(); }

void CrowdRenderer::release() {
  for (MeshGpu& m : meshes_) {
    glDeleteVertexArrays(1, &m.vao);
    glDeleteBuffers(1, &m.vertex_buffer);
    glDeleteBuffers(1, &m.index_buffer);
  }
  meshes_.clear();
  if (!initialized_) return;
  const GLuint buffers[] = {frame_ubo_,  palette_buffer_, instance_buffer_, wall_buffer_,
                            prop_buffer_, line_buffer_,    triangle_buffer_};
  glDeleteBuffers(7, buffers);
  glDeleteTextures(1, &palette_texture_);
  const GLuint vaos[] = {empty_vao_, shadow_vao_, wall_vao_, prop_vao_, line_vao_, triangle_vao_};
  glDeleteVertexArrays(6, vaos);
  initialized_ = false;
}

Status CrowdRenderer::init(const RendererConfig& config) {
  if (initialized_) return Status::Error("CrowdRenderer::init: already initialised");
  if (config.initial_agent_capacity < 1 || config.initial_joints_per_agent < 1 ||
      config.max_debug_lines < 0 || config.max_debug_triangles < 0) {
    return Status::Error("CrowdRenderer::init: capacities must be positive");
  }
  config_ = config;
  struct Pair {
    ShaderProgram* program;
    const char* vs;
    const char* fs;
  };
  const Pair programs[] = {{&skinned_program_, "skinned.vert", "lit.frag"},
                           {&static_program_, "static.vert", "lit.frag"},
                           {&ground_program_, "ground.vert", "ground.frag"},
                           {&shadow_program_, "shadow.vert", "shadow.frag"},
                           {&lines_program_, "lines.vert", "lines.frag"}};
  for (const Pair& p : programs) {
    Result<ShaderProgram> built = ShaderProgram::build(p.vs, p.fs);
    GK_RETURN_IF_ERROR(built);
    *p.program = std::move(built).value();
    // Every program shares the per-frame block at binding 0.
    const GLuint block = glGetUniformBlockIndex(p.program->id(), "Frame");
    if (block != GL_INVALID_INDEX) glUniformBlockBinding(p.program->id(), block, 0);
  }
  glUseProgram(skinned_program_.id());
  glUniform1i(skinned_program_.uniform("u_palette"), 0);
  lod_inflate_uniform_ = skinned_program_.uniform("u_lod_inflate_m");
  glUseProgram(0);

  initialized_ = true;  // from here release() owns whatever was created
  glGenBuffers(1, &frame_ubo_);
  glGenBuffers(1, &palette_buffer_);
  glGenTextures(1, &palette_texture_);
  glGenBuffers(1, &instance_buffer_);
  glGenBuffers(1, &wall_buffer_);
  glGenBuffers(1, &prop_buffer_);
  glGenBuffers(1, &line_buffer_);
  glGenBuffers(1, &triangle_buffer_);
  glGenVertexArrays(1, &empty_vao_);
  glGenVertexArrays(1, &shadow_vao_);
  glGenVertexArrays(1, &wall_vao_);
  glGenVertexArrays(1, &prop_vao_);
  glGenVertexArrays(1, &line_vao_);
  glGenVertexArrays(1, &triangle_vao_);
  glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texture_buffer_texels_);

  palette_capacity_matrices_ =
      static_cast<int64_t>(config.initial_agent_capacity) * config.initial_joints_per_agent;
  palette_capacity_matrices_ =
      std::min<int64_t>(palette_capacity_matrices_, max_texture_buffer_texels_ / 4);
  glBindBuffer(GL_TEXTURE_BUFFER, palette_buffer_);
  glBufferData(GL_TEXTURE_BUFFER, palette_capacity_matrices_ * sizeof(glm::mat4), nullptr,
               GL_STREAM_DRAW);
  glBindTexture(GL_TEXTURE_BUFFER, palette_texture_);
  glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, palette_buffer_);
  glBindTexture(GL_TEXTURE_BUFFER, 0);
  glBindBuffer(GL_TEXTURE_BUFFER, 0);

  instance_capacity_ = config.initial_agent_capacity;
  glBindBuffer(GL_ARRAY_BUFFER, instance_buffer_);
  glBufferData(GL_ARRAY_BUFFER, instance_capacity_ * sizeof(GpuInstance), nullptr, GL_STREAM_DRAW);
  glBindVertexArray(shadow_vao_);
  glEnableVertexAttribArray(7);
  glVertexAttribPointer(7, 4, GL_FLOAT, GL_FALSE, sizeof(GpuInstance),
                        reinterpret_cast<void*>(offsetof(GpuInstance, ground)));
  glVertexAttribDivisor(7, 1);

  // Lines and translucent triangles share the vertex layout and the program.
  const std::pair<GLuint, GLuint> batches[] = {{line_vao_, line_buffer_},
                                               {triangle_vao_, triangle_buffer_}};
  const size_t batch_vertices[] = {static_cast<size_t>(std::max(config.max_debug_lines, 1)) * 2,
                                   static_cast<size_t>(std::max(config.max_debug_triangles, 1)) * 3};
  for (int k = 0; k < 2; ++k) {
    glBindVertexArray(batches[k].first);
    glBindBuffer(GL_ARRAY_BUFFER, batches[k].second);
    glBufferData(GL_ARRAY_BUFFER, batch_vertices[k] * sizeof(LineVertex), nullptr, GL_STREAM_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(LineVertex), nullptr);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, sizeof(LineVertex),
                          reinterpret_cast<void*>(offsetof(LineVertex, color)));
  }
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);

  instances_.resize(instance_capacity_);
  visible_.resize(instance_capacity_);
  visible_lod_.resize(instance_capacity_);
  lines_.reserve(static_cast<size_t>(config.max_debug_lines) * 2);
  triangles_.reserve(static_cast<size_t>(config.max_debug_triangles) * 3);
  if (const GLenum error = glGetError(); error != GL_NO_ERROR) {
    return Status::Error("CrowdRenderer::init: GL error " + std::to_string(error));
  }
  return Status::Ok();
}

Status CrowdRenderer::upload_palettes(std::span<const glm::mat4> palettes, int joints_per_agent) {
  if (!initialized_) return Status::Error("upload_palettes: renderer not initialised");
  if (joints_per_agent < 1 || palettes.size() % static_cast<size_t>(joints_per_agent) != 0) {
    return Status::Error("upload_palettes: " + std::to_string(palettes.size()) +
                         " matrices is not a whole number of agents of " +
                         std::to_string(joints_per_agent) + " joints");
  }
  const int64_t num_matrices = static_cast<int64_t>(palettes.size());
  if (num_matrices * 4 > max_texture_buffer_texels_) {
    return Status::Error("upload_palettes: " + std::to_string(num_matrices) +
                         " matrices exceed the driver's texture buffer limit of " +
                         std::to_string(max_texture_buffer_texels_ / 4));
  }
  glBindBuffer(GL_TEXTURE_BUFFER, palette_buffer_);
  if (num_matrices > palette_capacity_matrices_) {
    palette_capacity_matrices_ = std::min<int64_t>(
        std::max(num_matrices, palette_capacity_matrices_ * 3 / 2), max_texture_buffer_texels_ / 4);
  }
  // Orphaning the store lets the driver hand us fresh memory while the GPU may still read the
  // previous frame's palettes, instead of stalling on them.
  glBufferData(GL_TEXTURE_BUFFER, palette_capacity_matrices_ * sizeof(glm::mat4), nullptr,
               GL_STREAM_DRAW);
  if (num_matrices > 0) {
    glBufferSubData(GL_TEXTURE_BUFFER, 0, num_matrices * sizeof(glm::mat4), palettes.data());
  }
  glBindBuffer(GL_TEXTURE_BUFFER, 0);
  num_palette_agents_ = static_cast<int>(num_matrices / joints_per_agent);
  joints_per_agent_ = joints_per_agent;
  if (lod_of_block_.size() < static_cast<size_t>(num_palette_agents_)) {
    lod_of_block_.resize(std::max<size_t>(num_palette_agents_, lod_of_block_.size() * 3 / 2),
                         kNoLod);
  }
  return Status::Ok();
}

int CrowdRenderer::cull_and_group(const OrbitCamera& camera, glm::ivec2 viewport_px,
                                  std::span<const AgentDraw> agents) {
  const Frustum frustum(camera.view_projection(viewport_px));
  // Depth along the view direction: the third row of the view matrix (negated: GL looks down -z).
  const glm::mat4 view = camera.view();
  const glm::vec4 depth_row(-view[0][2], -view[1][2], -view[2][2], -view[3][2]);
  const float y_scale = camera.projection(viewport_px)[1][1];
  std::fill(bucket_count_.begin(), bucket_count_.end(), 0);
  int num_visible = 0;
  for (size_t i = 0; i < agents.size(); ++i) {
    const AgentDraw& a = agents[i];
    const MeshGpu& m = meshes_[a.mesh];
    const glm::vec3 center = a.position + glm::vec3(0.0f, m.center_height_m, 0.0f);
    const bool finite =
        std::isfinite(center.x) && std::isfinite(center.y) && std::isfinite(center.z);
    if (!finite || (settings_.cull_agents && !frustum.intersects_sphere(center, m.radius_m))) {
      continue;
    }
    int level = 0;
    if (settings_.mesh_lod && m.num_lods > 1) {
      uint8_t& last = lod_of_block_[palette_block(a, i)];
      const float ppm =
          pixels_per_metre(y_scale, viewport_px.y, glm::dot(depth_row, glm::vec4(center, 1.0f)));
      level = choose_mesh_lod(std::span(m.lod_error_m).first(m.num_lods), ppm,
                              settings_.mesh_lod_selection, last == kNoLod ? -1 : last);
      last = static_cast<uint8_t>(level);
    }
    visible_[num_visible] = static_cast<int>(i);
    visible_lod_[num_visible++] = static_cast<uint8_t>(level);
    ++bucket_count_[a.mesh * kMaxMeshLods + level];
  }
  // Counting sort by (mesh, level), so each one's instances are contiguous for its single draw.
  int first = 0;
  for (size_t b = 0; b < bucket_first_.size(); ++b) {
    bucket_first_[b] = first;
    first += bucket_count_[b];
  }
  for (int v = 0; v < num_visible; ++v) {
    const int i = visible_[v];
    const AgentDraw& a = agents[i];
    const float shadow = meshes_[a.mesh].shadow_radius_m * settings_.shadow_radius_scale;
    const auto base =
        static_cast<uint32_t>(palette_block(a, static_cast<size_t>(i)) * joints_per_agent_);
    instances_[bucket_first_[a.mesh * kMaxMeshLods + visible_lod_[v]]++] = {
        a.tint, base, glm::vec4(a.position, shadow), glm::vec4(a.offset, 0.0f)};
  }
  for (size_t b = 0; b < bucket_first_.size(); ++b) bucket_first_[b] -= bucket_count_[b];
  return num_visible;
}

Status CrowdRenderer::draw(const OrbitCamera& camera, glm::ivec2 viewport_px,
                           std::span<const AgentDraw> agents) {
  return draw_region(camera, glm::ivec2(0), viewport_px, agents);
}

Status CrowdRenderer::draw_region(const OrbitCamera& camera, glm::ivec2 origin_px,
                                  glm::ivec2 viewport_px, std::span<const AgentDraw> agents) {
  if (!initialized_) return Status::Error("draw: renderer not initialised");
  if (viewport_px.x < 1 || viewport_px.y < 1) {
    return Status::Error("draw: bad viewport " + std::to_string(viewport_px.x) + "x" +
                         std::to_string(viewport_px.y));
  }
  for (size_t i = 0; i < agents.size(); ++i) {
    const int64_t palette = palette_block(agents[i], i);
    if (palette < 0 || palette >= num_palette_agents_) {
      return Status::Error("draw: agent " + std::to_string(i) + " uses palette block " +
                           std::to_string(palette) + " but palettes for " +
                           std::to_string(num_palette_agents_) + " were uploaded");
    }
    const int mesh = agents[i].mesh;
    if (mesh < 0 || mesh >= num_meshes()) {
      return Status::Error("draw: agent " + std::to_string(i) + " has mesh id " +
                           std::to_string(mesh) + ", only " + std::to_string(num_meshes()) +
                           " meshes were added");
    }
    if (meshes_[mesh].num_joints > joints_per_agent_) {
      return Status::Error("draw: mesh " + std::to_string(mesh) + " uses " +
                           std::to_string(meshes_[mesh].num_joints) + " joints, palettes have " +
                           std::to_string(joints_per_agent_) + " per agent");
    }
  }
  grow_to(&instances_, agents.size());
  grow_to(&visible_, agents.size());
  grow_to(&visible_lod_, agents.size());

  stats_ = {};
  stats_.agents_submitted = static_cast<int>(agents.size());
  const int num_visible = cull_and_group(camera, viewport_px, agents);
  stats_.agents_visible = num_visible;
  stats_.agents_culled = stats_.agents_submitted - num_visible;

  glBindBuffer(GL_ARRAY_BUFFER, instance_buffer_);
  if (num_visible > instance_capacity_) {
    instance_capacity_ = std::max(num_visible, instance_capacity_ * 3 / 2);
  }
  glBufferData(GL_ARRAY_BUFFER, instance_capacity_ * sizeof(GpuInstance), nullptr, GL_STREAM_DRAW);
  glBufferSubData(GL_ARRAY_BUFFER, 0, num_visible * sizeof(GpuInstance), instances_.data());
  glBindBuffer(GL_ARRAY_BUFFER, 0);

  upload_frame_block(camera, viewport_px);
  glViewport(origin_px.x, origin_px.y, viewport_px.x, viewport_px.y);
  // The scissor keeps the clear inside the region (split screen); an UI pass may have left it on
  // with another rectangle.
  glEnable(GL_SCISSOR_TEST);
  glScissor(origin_px.x, origin_px.y, viewport_px.x, viewport_px.y);
  glDisable(GL_CULL_FACE);  // enabled per mesh in draw_agents when its winding allows
  glCullFace(GL_BACK);
  glFrontFace(GL_CCW);
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  const glm::vec3 clear = glm::pow(settings_.fog_color, glm::vec3(1.0f / 2.2f));
  glClearColor(clear.x, clear.y, clear.z, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);

  if (settings_.draw_ground) draw_ground();
  if (settings_.draw_walls) draw_walls();
  draw_agents();
  if (settings_.draw_shadows && num_visible > 0) draw_shadows(num_visible);
  if (settings_.draw_lines) {
    draw_triangles();
    draw_lines();
  }
  stats_.lines_dropped = dropped_lines_;
  stats_.triangles_dropped = dropped_triangles_;
  lines_.clear();
  triangles_.clear();
  dropped_lines_ = 0;
  dropped_triangles_ = 0;
  glDisable(GL_SCISSOR_TEST);
  glBindVertexArray(0);
  glUseProgram(0);
  if (const GLenum error = glGetError(); error != GL_NO_ERROR) {
    return Status::Error("draw: GL error " + std::to_string(error));
  }
  return Status::Ok();
}

void CrowdRenderer::draw_agents() {
  glUseProgram(skinned_program_.id());
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_BUFFER, palette_texture_);
  glBindBuffer(GL_ARRAY_BUFFER, instance_buffer_);
  for (size_t b = 0; b < bucket_count_.size(); ++b) {
    const int count = bucket_count_[b];
    if (count == 0) continue;
    const MeshGpu& m = meshes_[b / kMaxMeshLods];
    const int level = static_cast<int>(b % kMaxMeshLods);
    if (m.cull_back_faces && settings_.cull_back_faces) {
      glEnable(GL_CULL_FACE);
    } else {
      glDisable(GL_CULL_FACE);
    }
    glBindVertexArray(m.vao);
    // GL 3.3 has no base-instance draw, so the instance attributes are pointed at this bucket's
    // slice; that is state inside the VAO and costs nothing like a buffer upload.
    const size_t base = static_cast<size_t>(bucket_first_[b]) * sizeof(GpuInstance);
    glVertexAttribPointer(5, 3, GL_FLOAT, GL_FALSE, sizeof(GpuInstance),
                          reinterpret_cast<void*>(base + offsetof(GpuInstance, tint)));
    glVertexAttribIPointer(6, 1, GL_UNSIGNED_INT, sizeof(GpuInstance),
                           reinterpret_cast<void*>(base + offsetof(GpuInstance, palette_base)));
    glVertexAttribPointer(8, 3, GL_FLOAT, GL_FALSE, sizeof(GpuInstance),
                          reinterpret_cast<void*>(base + offsetof(GpuInstance, offset)));
    glUniform1f(lod_inflate_uniform_, m.lod_inflate_m[level]);
    const size_t first_byte = static_cast<size_t>(m.lod_first[level]) * sizeof(uint32_t);
    glDrawElementsInstanced(GL_TRIANGLES, m.lod_count[level], GL_UNSIGNED_INT,
                            reinterpret_cast<void*>(first_byte), count);
    ++stats_.draw_calls;
    ++stats_.skinned_draw_calls;
    stats_.agents_per_lod[level] += count;
    stats_.agent_triangles += static_cast<int64_t>(count) * (m.lod_count[level] / 3);
  }
  glDisable(GL_CULL_FACE);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glBindTexture(GL_TEXTURE_BUFFER, 0);
}

}  // namespace gk
