#include "render/camera.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_access.hpp>
#include <glm/gtc/matrix_transform.hpp>

namespace gk {

glm::vec3 OrbitCamera::eye() const {
  const float c = std::cos(pitch_rad);
  return target +
         distance_m * glm::vec3(c * std::sin(yaw_rad), std::sin(pitch_rad), c * std::cos(yaw_rad));
}

glm::mat4 OrbitCamera::view() const {
  return glm::lookAt(eye(), target, glm::vec3(0.0f, 1.0f, 0.0f));
}

glm::mat4 OrbitCamera::projection(glm::ivec2 viewport_px) const {
  const float aspect = static_cast<float>(std::max(viewport_px.x, 1)) /
                       static_cast<float>(std::max(viewport_px.y, 1));
  return glm::perspective(glm::radians(fov_y_deg), aspect, near_m, far_m);
}

glm::mat4 OrbitCamera::view_projection(glm::ivec2 viewport_px) const {
  return projection(viewport_px) * view();
}

ProjectedPoint OrbitCamera::project(const glm::vec3& world, glm::ivec2 viewport_px) const {
  const glm::vec4 clip = view_projection(viewport_px) * glm::vec4(world, 1.0f);
  ProjectedPoint out;
  out.in_front = clip.w > 1e-6f;
  if (!out.in_front) return out;
  const glm::vec3 ndc = glm::vec3(clip) / clip.w;
  out.pixel.x = (ndc.x * 0.5f + 0.5f) * static_cast<float>(viewport_px.x);
  out.pixel.y = (0.5f - ndc.y * 0.5f) * static_cast<float>(viewport_px.y);
  out.depth = ndc.z * 0.5f + 0.5f;
  return out;
}

Ray OrbitCamera::pick_ray(glm::vec2 pixel, glm::ivec2 viewport_px) const {
  const glm::mat4 inverse = glm::inverse(view_projection(viewport_px));
  const float x = pixel.x / static_cast<float>(std::max(viewport_px.x, 1)) * 2.0f - 1.0f;
  const float y = 1.0f - pixel.y / static_cast<float>(std::max(viewport_px.y, 1)) * 2.0f;
  glm::vec4 near_point = inverse * glm::vec4(x, y, -1.0f, 1.0f);
  glm::vec4 far_point = inverse * glm::vec4(x, y, 1.0f, 1.0f);
  near_point /= near_point.w;
  far_point /= far_point.w;
  Ray ray;
  ray.origin = eye();
  ray.direction = glm::normalize(glm::vec3(far_point) - glm::vec3(near_point));
  return ray;
}

void OrbitCamera::orbit(float delta_yaw_rad, float delta_pitch_rad) {
  yaw_rad = std::remainder(yaw_rad + delta_yaw_rad, 2.0f * glm::pi<float>());
  pitch_rad = std::clamp(pitch_rad + delta_pitch_rad, -kMaxPitchRad, kMaxPitchRad);
}

void OrbitCamera::pan(glm::vec2 delta_px, glm::ivec2 viewport_px) {
  // Metres per pixel at the target's depth, so the scene follows the cursor.
  const float metres_per_px = 2.0f * distance_m * std::tan(glm::radians(fov_y_deg) * 0.5f) /
                              static_cast<float>(std::max(viewport_px.y, 1));
  const glm::mat4 v = view();
  const glm::vec3 right(glm::row(v, 0));
  const glm::vec3 up(glm::row(v, 1));
  target += (-delta_px.x * right + delta_px.y * up) * metres_per_px;
}

void OrbitCamera::zoom(float factor) {
  if (!(factor > 0.0f)) return;  // also rejects NaN from a bad input event
  distance_m = std::clamp(distance_m * factor, near_m * 2.0f, far_m * 0.5f);
}

void OrbitCamera::zoom_about(glm::vec2 pixel, glm::ivec2 viewport_px, float factor) {
  if (!(factor > 0.0f)) return;
  const std::optional<glm::vec3> hit = intersect_ground(pick_ray(pixel, viewport_px));
  const float before = distance_m;
  zoom(factor);
  if (!hit) return;
  // Scaling the whole camera (eye and target) about the hit point keeps the view direction, so
  // the hit projects to the same pixel; the clamped factor is the one that was applied.
  const float applied = distance_m / before;
  target = *hit + (target - *hit) * applied;
}

std::optional<glm::vec3> intersect_ground(const Ray& ray, float height_m) {
  if (std::abs(ray.direction.y) < 1e-6f) return std::nullopt;
  const float t = (height_m - ray.origin.y) / ray.direction.y;
  if (t < 0.0f) return std::nullopt;
  return ray.origin + t * ray.direction;
}

Frustum::Frustum(const glm::mat4& m) {
  // Gribb & Hartmann: each clip-space inequality -w <= x <= w etc. is a plane in world space.
  const glm::vec4 r0 = glm::row(m, 0), r1 = glm::row(m, 1), r2 = glm::row(m, 2),
                  r3 = glm::row(m, 3);
  planes_ = {r3 + r0, r3 - r0, r3 + r1, r3 - r1, r3 + r2, r3 - r2};
  for (glm::vec4& p : planes_) p /= glm::length(glm::vec3(p));
}

bool Frustum::intersects_sphere(const glm::vec3& center, float radius) const {
  for (const glm::vec4& p : planes_) {
    if (glm::dot(glm::vec3(p), center) + p.w < -radius) return false;
  }
  return true;
}

}  // namespace gk
