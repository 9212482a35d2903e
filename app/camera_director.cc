#include "app/camera_director.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/constants.hpp>

namespace gk::app {
namespace {

// Half-lives [s]: the follow is quick enough that a turning agent stays near the centre, slow
// enough to smooth the pelvis sway; closing in and pulling out are camera moves a viewer follows.
constexpr float kFollowHalflife_s = 0.2f;
constexpr float kCloseInHalflife_s = 0.5f;
constexpr float kPullOutHalflife_s = 0.8f;
// Backing away as a twin draws ahead: short, so that the distance does not lag a growing gap
// (a spring toward a goal moving at v lags it by about 2.9 v halflife).
constexpr float kTwinHalflife_s = 0.1f;
// A twin's head and the label over it: from the ground up to here [m] must be in view.
constexpr float kTwinLabelTop_m = 2.3f;

float spring_omega(float halflife_s) {
  // Holden's critically damped spring: damping 4 ln2 / halflife, omega its half.
  return 2.0f * 0.69314718f / std::max(halflife_s, 1e-4f);
}

// Shortest signed angle from a to b [rad].
float angle_to(float a, float b) { return std::remainder(b - a, 2.0f * glm::pi<float>()); }

}  // namespace

void spring_step(float* x, float* v, float goal, float goal_velocity, float halflife_s,
                 float dt_s) {
  // In the goal's frame the gap e = x - goal obeys e'' = -w^2 e - 2 w e', solved exactly:
  // e(t) = (e0 + (e0' + w e0) t) exp(-w t).
  const float w = spring_omega(halflife_s);
  const float e0 = *x - goal, de0 = *v - goal_velocity;
  const float j1 = de0 + w * e0;
  const float decay = std::exp(-w * dt_s);
  *x = goal + goal_velocity * dt_s + (e0 + j1 * dt_s) * decay;
  *v = goal_velocity + (de0 - w * j1 * dt_s) * decay;
}

void spring_step(glm::vec3* x, glm::vec3* v, const glm::vec3& goal, const glm::vec3& goal_velocity,
                 float halflife_s, float dt_s) {
  for (int k = 0; k < 3; ++k) {
    spring_step(&(*x)[k], &(*v)[k], goal[k], goal_velocity[k], halflife_s, dt_s);
  }
}

float distance_to_show(const OrbitCamera& camera, std::span<const glm::vec3> points,
                       glm::ivec2 view_px, float margin, float min_distance_m,
                       int bottom_inset_px) {
  OrbitCamera c = camera;
  const glm::vec2 lo(margin * static_cast<float>(view_px.y));
  const glm::vec2 hi =
      glm::vec2(view_px) - lo - glm::vec2(0.0f, static_cast<float>(std::max(bottom_inset_px, 0)));
  for (c.distance_m = std::max(min_distance_m, 0.5f); c.distance_m < 80.0f;
       c.distance_m *= 1.01f) {
    bool all = true;
    for (const glm::vec3& p : points) {
      const ProjectedPoint q = c.project(p, view_px);
      if (!q.in_front || q.pixel.x < lo.x || q.pixel.y < lo.y || q.pixel.x > hi.x ||
          q.pixel.y > hi.y) {
        all = false;
        break;
      }
    }
    if (all) return c.distance_m;
  }
  return 80.0f;
}

void CameraDirector::follow(int64_t id, float distance_m, float pitch_rad) {
  id_ = id;
  user_zoomed_ = false;
  seen_ = false;
  follow_distance_m_ = distance_m;
  follow_pitch_rad_ = pitch_rad;
  closing_in_ = true;
  close_in_started_ = false;
  pulling_out_ = false;
}

void CameraDirector::update(double sim_time_s, float dt_s,
                            const std::optional<FollowedAgent>& followed, OrbitCamera* camera) {
  dt_s = std::clamp(dt_s, 0.0f, 0.25f);  // a stalled frame must not fling the camera
  if (pull_out_at_s_ && sim_time_s >= *pull_out_at_s_) {
    pull_out_at_s_.reset();
    pulling_out_ = true;
    id_ = -1;
    yaw_velocity_ = 0.0f;
  }
  if (pulling_out_) {
    spring_step(&camera->target, &target_velocity_, overview_.target, glm::vec3(0.0f),
                kPullOutHalflife_s, dt_s);
    spring_step(&camera->distance_m, &distance_velocity_, overview_.distance_m, 0.0f,
                kPullOutHalflife_s, dt_s);
    spring_step(&camera->pitch_rad, &pitch_velocity_, overview_.pitch_rad, 0.0f,
                kPullOutHalflife_s, dt_s);
    float yaw = camera->yaw_rad;
    spring_step(&yaw, &yaw_velocity_, yaw + angle_to(yaw, overview_.yaw_rad), 0.0f,
                kPullOutHalflife_s, dt_s);
    camera->yaw_rad = std::remainder(yaw, 2.0f * glm::pi<float>());
    if (std::abs(camera->distance_m - overview_.distance_m) < 0.01f * overview_.distance_m &&
        glm::length(camera->target - overview_.target) < 0.05f) {
      pulling_out_ = false;
    }
    return;
  }
  if (id_ < 0) return;
  if (!followed) {
    // It left the scene: nothing to follow, show the whole scene. A replayed pedestrian that has
    // not appeared yet is waited for.
    if (seen_) id_ = -1, pulling_out_ = true, pull_out_at_s_.reset();
    return;
  }
  seen_ = true;
  const glm::vec3 between =
      followed->twin ? 0.5f * (followed->position + *followed->twin) : followed->position;
  const glm::vec3 goal = between + glm::vec3(0.0f, kFollowHeight_m, 0.0f);
  const glm::vec3 goal_velocity(followed->velocity_xz.x, 0.0f, followed->velocity_xz.y);
  // Both places of a twin in view: the feet, and the head with a label's height above it.
  float goal_distance_m = follow_distance_m_;
  if (followed->twin && !user_zoomed_) {
    OrbitCamera aim = *camera;
    aim.target = goal;
    // Around the feet the ring's 0.5 m (with some room), over the head the label.
    const glm::vec3 up(0.0f, kTwinLabelTop_m, 0.0f), ex(0.7f, 0.0f, 0.0f), ez(0.0f, 0.0f, 0.7f);
    std::vector<glm::vec3> points;
    for (const glm::vec3& p : {followed->position, *followed->twin}) {
      points.insert(points.end(), {p + up, p + ex, p - ex, p + ez, p - ez});
    }
    goal_distance_m =
        distance_to_show(aim, points, view_px_, 0.08f, follow_distance_m_, bottom_inset_px_);
  }
  if (closing_in_ && !close_in_started_) {
    close_in_started_ = true;
    follow_distance_m_ = std::min(follow_distance_m_, camera->distance_m);
  }
  if (snap_) {
    snap_ = false;
    camera->target = goal;
    target_velocity_ = goal_velocity;
    if (closing_in_) {
      camera->distance_m = goal_distance_m;
      camera->pitch_rad = follow_pitch_rad_;
      closing_in_ = false;
    } else if (followed->twin && !user_zoomed_) {
      camera->distance_m = goal_distance_m;
    }
    return;
  }
  spring_step(&camera->target, &target_velocity_, goal, goal_velocity, kFollowHalflife_s, dt_s);
  if (followed->twin && !user_zoomed_ && !closing_in_) {
    spring_step(&camera->distance_m, &distance_velocity_, goal_distance_m, 0.0f, kTwinHalflife_s,
                dt_s);
  }
  if (closing_in_) {
    spring_step(&camera->distance_m, &distance_velocity_, goal_distance_m, 0.0f,
                kCloseInHalflife_s, dt_s);
    spring_step(&camera->pitch_rad, &pitch_velocity_, follow_pitch_rad_, 0.0f, kCloseInHalflife_s,
                dt_s);
    if (std::abs(camera->distance_m - goal_distance_m) < 0.01f &&
        std::abs(camera->pitch_rad - follow_pitch_rad_) < 1e-3f) {
      closing_in_ = false;
    }
  }
}

}  // namespace gk::app
