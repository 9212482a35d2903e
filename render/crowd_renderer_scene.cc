// The scene around the agents: per-frame uniform block, ground grid, walls and props, contact
// shadows, debug lines and translucent debug triangles (CrowdRenderer members kept apart from the
// skinning path).
#include <cmath>
#include <cstddef>
#include <string>

#include "render/crowd_renderer.h"

namespace gk {
namespace {

// std140 mirror of the Frame block in shaders/common.glsl: only mat4 and vec4 members, so the
// C++ layout matches std140 without padding rules.
struct FrameBlock {
  glm::mat4 view_proj;
  glm::vec4 eye;
  glm::vec4 sun_dir;
  glm::vec4 sun_color;
  glm::vec4 sky_color;
  glm::vec4 ground_color;
  glm::vec4 fog;
  glm::vec4 params;
  glm::vec4 ground_albedo;
  glm::vec4 grid_color;
  glm::vec4 ground_rect;
};
static_assert(sizeof(FrameBlock) == 64 + 10 * 16);

struct WallVertex {  // matches static.vert
  glm::vec3 position;
  glm::vec3 normal;
  glm::vec3 color;
};

void add_quad(std::vector<WallVertex>* out, const glm::vec3& a, const glm::vec3& b,
              const glm::vec3& c, const glm::vec3& d, const glm::vec3& normal,
              const glm::vec3& color) {
  for (const glm::vec3& p : {a, b, c, a, c, d}) out->push_back({p, normal, color});
}

// Position, normal and colour attributes of static lit geometry (walls, props) in `vao`.
void upload_static(GLuint vao, GLuint buffer, const std::vector<WallVertex>& vertices) {
  glBindVertexArray(vao);
  glBindBuffer(GL_ARRAY_BUFFER, buffer);
  glBufferData(GL_ARRAY_BUFFER, vertices.size() * sizeof(WallVertex), vertices.data(),
               GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(WallVertex), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(WallVertex),
                        reinterpret_cast<void*>(offsetof(WallVertex, normal)));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, sizeof(WallVertex),
                        reinterpret_cast<void*>(offsetof(WallVertex, color)));
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
}

bool finite3(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

void CrowdRenderer::upload_frame_block(const OrbitCamera& camera, glm::ivec2 viewport_px) {
  const RenderSettings& s = settings_;
  FrameBlock block;
  block.view_proj = camera.view_projection(viewport_px);
  block.eye = glm::vec4(camera.eye(), 1.0f);
  block.sun_dir = glm::vec4(glm::normalize(s.sun_direction), 0.0f);
  block.sun_color = glm::vec4(s.sun_color, 0.0f);
  block.sky_color = glm::vec4(s.sky_color, 0.0f);
  block.ground_color = glm::vec4(s.ground_bounce_color, 0.0f);
  block.fog = glm::vec4(s.fog_color, std::max(s.fog_density_per_m, 0.0f));
  block.params = glm::vec4(s.rim_strength, s.shadow_opacity, std::max(s.grid_spacing_m, 1e-3f),
                           std::max(s.grid_major_every, 1.0f));
  block.ground_albedo = glm::vec4(s.ground_albedo, 0.0f);
  block.grid_color = glm::vec4(s.grid_color, 0.0f);
  block.ground_rect = glm::vec4(camera.target.x, camera.target.z, s.ground_half_extent_m, 0.0f);
  glBindBuffer(GL_UNIFORM_BUFFER, frame_ubo_);
  glBufferData(GL_UNIFORM_BUFFER, sizeof(FrameBlock), &block, GL_STREAM_DRAW);
  glBindBuffer(GL_UNIFORM_BUFFER, 0);
  glBindBufferBase(GL_UNIFORM_BUFFER, 0, frame_ubo_);
}

void CrowdRenderer::draw_ground() {
  glUseProgram(ground_program_.id());
  glBindVertexArray(empty_vao_);
  glDrawArrays(GL_TRIANGLES, 0, 6);
  ++stats_.draw_calls;
}

Status CrowdRenderer::set_walls(std::span<const glm::vec4> segments) {
  if (!initialized_) return Status::Error("set_walls: renderer not initialised");
  const float h = settings_.wall_height_m;
  const float t = 0.5f * settings_.wall_thickness_m;
  if (!(h > 0.0f) || !(t > 0.0f)) {
    return Status::Error("set_walls: wall_height_m and wall_thickness_m must be > 0");
  }
  std::vector<WallVertex> vertices;
  vertices.reserve(segments.size() * 30);
  const glm::vec3 color = settings_.wall_color;
  for (size_t i = 0; i < segments.size(); ++i) {
    const glm::vec4& s = segments[i];
    if (!std::isfinite(s.x) || !std::isfinite(s.y) || !std::isfinite(s.z) || !std::isfinite(s.w)) {
      return Status::Error("set_walls: segment " + std::to_string(i) + " is not finite");
    }
    glm::vec2 p0(s.x, s.y), p1(s.z, s.w);
    const float length = glm::length(p1 - p0);
    if (length < 1e-6f) continue;  // a degenerate segment has no wall to show
    const glm::vec2 d = (p1 - p0) / length;
    const glm::vec2 side(d.y, -d.x);
    // Extending the ends by half the thickness closes the corners where walls meet.
    p0 -= d * t;
    p1 += d * t;
    const glm::vec2 c2[4] = {p0 + side * t, p1 + side * t, p1 - side * t, p0 - side * t};
    glm::vec3 lo[4], hi[4];
    for (int k = 0; k < 4; ++k) {
      lo[k] = glm::vec3(c2[k].x, 0.0f, c2[k].y);
      hi[k] = glm::vec3(c2[k].x, h, c2[k].y);
    }
    add_quad(&vertices, hi[0], hi[1], hi[2], hi[3], glm::vec3(0.0f, 1.0f, 0.0f), color);  // top
    const glm::vec3 centre = 0.25f * (lo[0] + lo[1] + lo[2] + lo[3]);
    for (int k = 0; k < 4; ++k) {
      const int j = (k + 1) % 4;
      const glm::vec3 outward = glm::normalize(0.5f * (lo[k] + lo[j]) - centre);
      add_quad(&vertices, lo[k], lo[j], hi[j], hi[k], outward, color);
    }
  }
  num_wall_vertices_ = static_cast<GLsizei>(vertices.size());
  upload_static(wall_vao_, wall_buffer_, vertices);
  return Status::Ok();
}

Status CrowdRenderer::set_props(std::span<const PropBox> boxes) {
  if (!initialized_) return Status::Error("set_props: renderer not initialised");
  std::vector<WallVertex> vertices;
  vertices.reserve(boxes.size() * 36);
  for (size_t i = 0; i < boxes.size(); ++i) {
    const PropBox& b = boxes[i];
    if (!finite3(b.center) || !finite3(b.half_size) || !std::isfinite(b.yaw_rad) ||
        !finite3(b.color)) {
      return Status::Error("set_props: box " + std::to_string(i) + " is not finite");
    }
    if (!(b.half_size.x > 0.0f && b.half_size.y > 0.0f && b.half_size.z > 0.0f)) {
      return Status::Error("set_props: box " + std::to_string(i) + " has a size <= 0");
    }
    const glm::vec3 ax(std::cos(b.yaw_rad), 0.0f, -std::sin(b.yaw_rad));  // local +x
    const glm::vec3 az(std::sin(b.yaw_rad), 0.0f, std::cos(b.yaw_rad));   // local +z
    const glm::vec3 ay(0.0f, 1.0f, 0.0f);
    const glm::vec3 x = ax * b.half_size.x, y = ay * b.half_size.y, z = az * b.half_size.z;
    const glm::vec3 c = b.center;
    // Each face: its centre offset (= its outward normal times the half size) and two in-plane
    // half axes u, v with u x v along the normal.
    const glm::vec3 faces[6][3] = {{z, x, y}, {-z, -x, y}, {x, -z, y},
                                   {-x, z, y}, {y, x, -z}, {-y, x, z}};
    for (const auto& f : faces) {
      const glm::vec3 centre = c + f[0];
      add_quad(&vertices, centre - f[1] - f[2], centre + f[1] - f[2], centre + f[1] + f[2],
               centre - f[1] + f[2], glm::normalize(f[0]), b.color);
    }
  }
  num_prop_vertices_ = static_cast<GLsizei>(vertices.size());
  upload_static(prop_vao_, prop_buffer_, vertices);
  return Status::Ok();
}

void CrowdRenderer::draw_walls() {
  if (num_wall_vertices_ == 0 && num_prop_vertices_ == 0) return;
  glUseProgram(static_program_.id());
  if (num_wall_vertices_ > 0) {
    glBindVertexArray(wall_vao_);
    glDrawArrays(GL_TRIANGLES, 0, num_wall_vertices_);
    ++stats_.draw_calls;
  }
  if (num_prop_vertices_ > 0) {
    glBindVertexArray(prop_vao_);
    glDrawArrays(GL_TRIANGLES, 0, num_prop_vertices_);
    ++stats_.draw_calls;
  }
}

void CrowdRenderer::draw_shadows(int num_visible) {
  glUseProgram(shadow_program_.id());
  glBindVertexArray(shadow_vao_);
  glDepthMask(GL_FALSE);  // shadows darken the ground but must not hide each other
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(-1.0f, -4.0f);
  glDrawArraysInstanced(GL_TRIANGLES, 0, 6, num_visible);
  ++stats_.draw_calls;
  glDisable(GL_POLYGON_OFFSET_FILL);
  glDisable(GL_BLEND);
  glDepthMask(GL_TRUE);
}

void CrowdRenderer::add_line(const glm::vec3& a, const glm::vec3& b, const glm::vec3& color) {
  // Never reallocate per frame: beyond the fixed capacity lines are dropped and counted.
  if (lines_.size() + 2 > static_cast<size_t>(config_.max_debug_lines) * 2) {
    ++dropped_lines_;
    return;
  }
  const glm::vec4 c(color, 1.0f);
  lines_.push_back({a, c});
  lines_.push_back({b, c});
}

void CrowdRenderer::add_triangle(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c,
                                 const glm::vec4& color) {
  if (triangles_.size() + 3 > static_cast<size_t>(config_.max_debug_triangles) * 3) {
    ++dropped_triangles_;
    return;
  }
  triangles_.push_back({a, color});
  triangles_.push_back({b, color});
  triangles_.push_back({c, color});
}

void CrowdRenderer::draw_triangles() {
  if (triangles_.empty()) return;
  glUseProgram(lines_program_.id());
  glBindVertexArray(triangle_vao_);
  glBindBuffer(GL_ARRAY_BUFFER, triangle_buffer_);
  glBufferSubData(GL_ARRAY_BUFFER, 0, triangles_.size() * sizeof(LineVertex), triangles_.data());
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  if (settings_.lines_on_top) glDisable(GL_DEPTH_TEST);
  // Translucent and seen from both sides; they must not hide each other in the depth buffer. The
  // frame's alpha stays 1 so captured images are opaque.
  glDepthMask(GL_FALSE);
  glEnable(GL_BLEND);
  glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ZERO, GL_ONE);
  glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(triangles_.size()));
  glDisable(GL_BLEND);
  glDepthMask(GL_TRUE);
  glEnable(GL_DEPTH_TEST);
  ++stats_.draw_calls;
  stats_.triangles_drawn = static_cast<int>(triangles_.size() / 3);
}

void CrowdRenderer::draw_lines() {
  if (lines_.empty()) return;
  glUseProgram(lines_program_.id());
  glBindVertexArray(line_vao_);
  glBindBuffer(GL_ARRAY_BUFFER, line_buffer_);
  glBufferSubData(GL_ARRAY_BUFFER, 0, lines_.size() * sizeof(LineVertex), lines_.data());
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  if (settings_.lines_on_top) glDisable(GL_DEPTH_TEST);
  glDrawArrays(GL_LINES, 0, static_cast<GLsizei>(lines_.size()));
  glEnable(GL_DEPTH_TEST);
  ++stats_.draw_calls;
  stats_.lines_drawn = static_cast<int>(lines_.size() / 2);
}

}  // namespace gk
