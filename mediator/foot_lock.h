#pragma once
// The foot-lock state machine of one foot as a small pure function (state in, state and toe goal
// out), so it can be tested alone. Pose synthesis runs it per foot and turns the goal into leg IK.
//
// A foot the clips put on the ground is pinned where it was drawn; it is held until the clips lift
// it, then released: the difference between where it was drawn and where the clip has it becomes
// an offset that the foot sheds over the clips' own swing (smoothly in the swing's progress, gone
// when the clip lands the foot), so no joint snaps, the correction happens in the air, and the
// swing keeps the clip's own height. A foot that lands settles onto the floor through a decaying
// offset (a critically damped spring, exact for any step). A pinned foot left far behind by a turn
// or a drift re-plants, while the other foot is pinned, with a short step as high as the clips'
// own swing.

#include <cstdint>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace gk {

enum class FootLockState : uint8_t { kFree, kLocked, kReleasing, kStepping };

// One foot's lock (explicit state; the caller stores it).
struct FootLock {
  FootLockState state = FootLockState::kFree;
  glm::vec3 target{0.0f};      // pinned toe (world) [m]; y is the floor
  glm::vec3 offset{0.0f};      // inertialization offset added to the goal [m]
  glm::vec3 offset_vel{0.0f};  // its rate [m/s]
  glm::vec3 from{0.0f};        // stepping: where the step started [m]
  float timer_s = 0.0f;        // stepping: time since the step started [s]
  glm::vec3 step_to{0.0f};     // stepping: where it is set down (chosen as it starts to lower) [m]
  glm::vec3 last_goal{0.0f};   // the goal returned last frame [m]
  glm::vec3 goal_vel{0.0f};    // its velocity [m/s] (a step turned release keeps its speed)
  float shed = 0.0f;           // releasing: share of the release offset shed so far, 0..1
  float swing_from = 0.0f;     // releasing: the swing progress at release
  float shed_from = 0.0f;      // releasing: share shed when that progress was taken
  float shed_goal = 0.0f;      // releasing: share the swing's progress asks for
  float released_s = 0.0f;     // releasing: time since the release [s]
  float release_time_s = 0.0f; // releasing: the shortest time to shed the offset in [s]
  float anim_speed = -1.0f;    // the clip's toe speed over the ground last frame [m/s] (< 0: none)
};

struct FootLockInput {
  glm::vec3 anim_toe{0.0f};        // the clip's toe this frame, placed in the world [m]
  glm::vec3 anim_toe_prev{0.0f};   // the clip's toe last frame [m]
  glm::vec3 drawn_toe_prev{0.0f};  // the toe as drawn last frame [m]
  bool fresh = false;              // the agent's first frame: nothing carries over
  bool plant = false;              // the clips put this foot on the ground (a lock may start)
  bool hold = false;               // the clips still have weight on it (a lock is kept)
  float swing_progress = 0.0f;     // the clips' swing of this foot, 0 at lift-off, 1 at landing
  bool other_locked = false;       // the other foot is pinned (one foot steps at a time)
  // Walking, the other foot is coming down or planted but not pinned yet: this one keeps its
  // weight (its lock) until the other has taken it over, as a trailing foot stays down until the
  // leading one is flat. (Running has a flight phase: no such wait.)
  bool other_landing = false;
  float floor_toe_m = 0.0f;        // where planted toes are (library floor) [m]
  // A ball this slow over the ground is at rest (clip analysis's "still": half the travel speed,
  // at least its capture-jitter floor) [m/s]. A plant pins the foot once its ball is at rest, or
  // once it has stopped slowing down: at its slowest, so the drawn foot stops with no jolt.
  float still_speed_m_s = 0.0f;
};

struct FootLockParams {
  float release_halflife_s = 0.06f;  // [s] halflife of the released foot's offset
  float step_distance_m = 0.25f;     // [m] a pinned foot this far from the clip's re-plants
  float step_time_s = 0.35f;         // [s] duration of a re-planting step
  float step_height_m = 0.05f;       // [m] its height (the clips' own swing)
  // [m/s] the clips' own peak swing speed: a released foot is never carried faster than this
  // toward the clip's foot (a long offset takes longer to shed; <= 0: no limit).
  float swing_speed_m_s = 0.0f;
};

// Advances one foot by dt_s and returns where its toe should be drawn (world, before any pelvis
// drop and floor clamp; the caller applies both).
glm::vec3 step_foot_lock(FootLock& lock, const FootLockInput& in, const FootLockParams& p,
                         float dt_s);

// Starts a re-planting step of a pinned foot from where it is drawn (from): used when the leg
// cannot reach where it is pinned while the clips still have the foot on the ground.
void start_foot_step(FootLock& lock, const glm::vec3& from);

// Lets a pinned or stepping foot go from where it is drawn (drawn_toe, moving at drawn_vel) to the
// clip's toe (anim_toe, moving at anim_vel) through an inertialization offset.
void release_foot_lock(FootLock& lock, const glm::vec3& drawn_toe, const glm::vec3& drawn_vel,
                       const glm::vec3& anim_toe, const glm::vec3& anim_vel);

}  // namespace gk
