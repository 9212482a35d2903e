#pragma once
// Orbit camera (target, yaw, pitch, distance, vertical fov) with the view/projection matrices,
// world <-> pixel mapping and a view frustum for culling. Pixels have their origin at the top-left
// corner of the viewport with y pointing down, like mouse coordinates and captured image rows.

#include <array>
#include <optional>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace gk {

struct Ray {
  glm::vec3 origin{0.0f};
  glm::vec3 direction{0.0f, 0.0f, -1.0f};  // unit length
};

struct ProjectedPoint {
  glm::vec2 pixel{0.0f};  // [px], may lie outside the viewport
  float depth = 0.0f;     // window depth in [0, 1] when in front and within near/far
  bool in_front = false;  // false for points behind the camera (pixel is then meaningless)
};

struct OrbitCamera {
  glm::vec3 target{0.0f, 1.0f, 0.0f};  // point orbited around [m]
  float yaw_rad = 0.0f;      // about +y; 0 puts the eye on +z of the target, looking toward -z
  float pitch_rad = 0.4f;    // elevation of the eye above the target [rad] [Limit: +-kMaxPitchRad]
  float distance_m = 12.0f;  // eye to target [m] [Limit: > near_m]
  // Vertical field of view [deg] [Limit: (0, 180)]. 30 deg, not 45: on a 16:9 frame 45 deg
  // vertical is 72 deg horizontal, and upright bodies near the edges of a tilted view lean out.
  float fov_y_deg = 30.0f;
  float near_m = 0.1f;
  float far_m = 500.0f;

  static constexpr float kMaxPitchRad = 1.55f;  // just short of straight down, keeps lookAt stable

  glm::vec3 eye() const;
  glm::mat4 view() const;
  glm::mat4 projection(glm::ivec2 viewport_px) const;
  glm::mat4 view_projection(glm::ivec2 viewport_px) const;

  // World point -> viewport pixel (top-left origin).
  ProjectedPoint project(const glm::vec3& world, glm::ivec2 viewport_px) const;
  // Ray from the eye through a pixel (top-left origin, pixel centres at +0.5).
  Ray pick_ray(glm::vec2 pixel, glm::ivec2 viewport_px) const;

  // Interaction helpers for the app: angles [rad], pan in pixels (the target moves with the
  // ground under the cursor at the target's depth), zoom as a distance factor (< 1 moves closer).
  void orbit(float delta_yaw_rad, float delta_pitch_rad);
  void pan(glm::vec2 delta_px, glm::ivec2 viewport_px);
  void zoom(float factor);
  // Zoom toward the cursor: the camera moves by `factor` (< 1 closer) about the ground point
  // (y = 0) under `pixel`, which stays under it; above the horizon this is zoom(factor).
  void zoom_about(glm::vec2 pixel, glm::ivec2 viewport_px, float factor);
};

// Where a ray meets the plane y = height_m; nullopt when parallel or behind the origin.
std::optional<glm::vec3> intersect_ground(const Ray& ray, float height_m = 0.0f);

// Six planes (a, b, c, d) with normals pointing inward, from a view-projection matrix.
class Frustum {
 public:
  explicit Frustum(const glm::mat4& view_projection);
  // Conservative: true when the sphere may be visible.
  bool intersects_sphere(const glm::vec3& center, float radius) const;

 private:
  std::array<glm::vec4, 6> planes_;
};

}  // namespace gk
