#pragma once
// Moves the orbit camera of the demo window and of `gaitkeeper render`: follows one agent close
// enough to see its feet (critically damped springs, so the stride's sway does not shake the view
// and a walking agent stays at the image centre instead of trailing behind it), and the opening
// shot: close on one agent, then, at a set simulated time, pulled out to the whole scene.

#include <cstdint>
#include <optional>
#include <span>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "render/camera.h"

namespace gk::app {

// Framing of a followed agent: close enough to see a foot slide, high enough to see it over the
// heads of a dense crowd.
inline constexpr float kFollowDistance_m = 8.0f;
inline constexpr float kFollowPitch_rad = 0.55f;  // 31 deg
inline constexpr float kFollowHeight_m = 0.9f;    // the camera aims at the hips

// The followed agent on this frame: ground position [m] and velocity [m/s].
struct FollowedAgent {
  glm::vec3 position{0.0f};
  glm::vec2 velocity_xz{0.0f};
  // A split whose halves run their own crowds (the feedback lesson) shows the same agent in two
  // places under one camera: its ground position [m] in the other half. The camera then aims
  // between the two and, until the user zooms, backs away until both bodies and the labels over
  // their heads are in view.
  std::optional<glm::vec3> twin;
};

class CameraDirector {
 public:
  // `overview` frames the whole scene: where a pull-out ends.
  void set_overview(const OrbitCamera& overview) { overview_ = overview; }
  const OrbitCamera& overview() const { return overview_; }

  // Follow `id` from now on; the camera closes in to `distance_m` and `pitch_rad` (unless the
  // distance is already smaller: a user who zoomed in stays there).
  void follow(int64_t id, float distance_m = kFollowDistance_m,
              float pitch_rad = kFollowPitch_rad);
  void stop_following() { id_ = -1; }
  bool following() const { return id_ >= 0; }
  int64_t followed_id() const { return id_; }
  // At simulated time `time_s` stop following and move to the overview (once).
  void pull_out_at(double time_s) { pull_out_at_s_ = time_s; }
  bool pull_out_pending() const { return pull_out_at_s_.has_value(); }
  // The user took the camera (orbit, zoom): scripted moves (closing in, the pull-out) stop;
  // following continues.
  void user_took_camera() {
    pull_out_at_s_.reset(), pulling_out_ = false, closing_in_ = false, user_zoomed_ = true;
  }
  // The size [px] of the view (one half of a split) the camera draws: what a twin is fitted into,
  // above `bottom_inset_px` (text drawn over the bottom of the view).
  void set_view(glm::ivec2 view_px, int bottom_inset_px = 0) {
    view_px_ = view_px, bottom_inset_px_ = bottom_inset_px;
  }
  // The next update jumps to its goal instead of moving there (the first frame of a shot).
  void snap() { snap_ = true; }

  // Advances the camera by `dt_s` [s] of drawing time at simulated time `sim_time_s`. `followed`
  // is the followed agent when it is in the frame; when an agent that was seen leaves, following
  // stops and the camera pulls out. Orbit and zoom the user applied to `camera` are kept; only the
  // parts being moved are driven.
  void update(double sim_time_s, float dt_s, const std::optional<FollowedAgent>& followed,
              OrbitCamera* camera);

 private:
  OrbitCamera overview_;
  int64_t id_ = -1;
  bool seen_ = false;  // the followed agent has appeared at least once
  float follow_distance_m_ = kFollowDistance_m;
  float follow_pitch_rad_ = kFollowPitch_rad;
  bool closing_in_ = false;  // distance and pitch still moving toward the follow framing
  bool close_in_started_ = false;
  std::optional<double> pull_out_at_s_;
  bool pulling_out_ = false;
  bool snap_ = false;
  bool user_zoomed_ = false;  // the user took the camera: a twin no longer moves the distance
  glm::ivec2 view_px_{16, 9};
  int bottom_inset_px_ = 0;
  glm::vec3 target_velocity_{0.0f};
  float distance_velocity_ = 0.0f;
  float pitch_velocity_ = 0.0f;
  float yaw_velocity_ = 0.0f;
};

// The distance [m], at least `min_distance_m`, from which `camera` (its target, yaw and pitch kept)
// shows every point of `points` inside a view of `view_px` with `margin` (a fraction of the view's
// height) to spare, and above the bottom `bottom_inset_px`; at most 80 m.
float distance_to_show(const OrbitCamera& camera, std::span<const glm::vec3> points,
                       glm::ivec2 view_px, float margin, float min_distance_m,
                       int bottom_inset_px = 0);

// One step of a critically damped spring toward a goal that moves at `goal_velocity`, exact for a
// goal moving at constant velocity: x'' = w^2 (goal - x) + 2 w (goal_velocity - v), w from the
// half-life [s] (the time in which the gap to a still goal halves).
void spring_step(float* x, float* v, float goal, float goal_velocity, float halflife_s, float dt_s);
void spring_step(glm::vec3* x, glm::vec3* v, const glm::vec3& goal, const glm::vec3& goal_velocity,
                 float halflife_s, float dt_s);

}  // namespace gk::app
