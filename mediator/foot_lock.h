#pragma once
// The foot-lock state machine of one foot as small pure functions (Holden's style: explicit state
// in, state out; the caller stores it), so each transition can be tested alone. Pose synthesis runs
// advance_foot_lock (step_foot_lock in place) per foot and turns the goal into leg IK.
//
// A foot the clips put on the ground is pinned where it was drawn (plant_foot); it is held until
// the clips lift it, then released (release_foot_lock): the difference between where it was drawn
// and where the clip has it becomes an offset that the foot sheds over the clips' own swing
// (smoothly in the swing's progress, gone when the clip lands the foot), so no joint snaps, the
// correction happens in the air, and the swing keeps the clip's own height. A foot that lands
// settles onto the floor through a decaying offset (a critically damped spring, exact for any
// step). A pinned toe follows the clip's down as the foot rolls onto its ball, and up while the
// other foot is pinned (pushing off onto the toes) or, in a run, all through the stance (no other
// foot takes the weight: the push-off is into the air); never while it alone bears a walker's
// weight. A pinned foot left far behind by a turn or a drift re-plants (start_foot_step), while
// the other foot is pinned, with a short step as high as the clips' own swing.
//
//   kFree      -> kLocked     plant_foot: the clips plant it and its ball has come to rest (or
//                             rests in the clips, moving no faster than twice the still speed),
//                             or the other foot is not pinned (this one takes the weight)
//   kReleasing -> kLocked     plant_foot: planted again before the offset was shed
//   kLocked    -> kReleasing  release_foot_lock: the clips lift it (the other foot is not landing);
//                             it sets off from rest (its rest carried on and shed)
//   kLocked    -> kStepping   start_foot_step: left too far behind while the other foot is pinned
//                             flat and the clips are not walking (their own swing re-places it);
//                             or (pose synthesis) a leg that cannot reach its pin, walking or
//                             not, while the clips keep weight on the foot and the other is
//                             pinned flat (not on its heel)
//   kStepping  -> kReleasing  release_foot_lock: the clips lift it before the step is done (the
//                             step's velocity is carried on and shed: no jump to the clip's)
//   kStepping  -> kLocked     the step has landed: pinned on the floor where the clip has the foot
//   kReleasing -> kFree       the offset is shed
//   any        -> kFree       fresh_foot_lock: an agent's first frame

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
  // Pinned: halflife the offset decays with (0: the landing's release_halflife_s; a glide's
  // shorter one settles the landing's height with it).
  float offset_halflife_s = 0.0f;
  glm::vec3 from{0.0f};         // stepping: where the step started [m]
  float timer_s = 0.0f;         // stepping: time since the step started [s]
  glm::vec3 step_to{0.0f};      // stepping: where it is set down (chosen as it starts to lower) [m]
  glm::vec3 step_to_vel{0.0f};  // stepping: its rate [m/s] (it follows the clip's foot on a spring)
  glm::vec3 last_goal{0.0f};    // the goal returned last frame [m]
  glm::vec3 goal_vel{0.0f};     // its velocity [m/s] (a step turned release keeps its speed)
  float shed = 0.0f;            // releasing: share of the release offset shed so far, 0..1
  float swing_from = 0.0f;      // releasing: the swing progress at release
  float last_progress = 0.0f;   // releasing: the swing progress last frame
  float shed_from = 0.0f;       // releasing: share shed when that progress was taken
  float shed_goal = 0.0f;       // releasing: share the swing's progress asks for
  float released_s = 0.0f;      // releasing: time since the release [s]
  float release_time_s = 0.0f;  // releasing: the shortest time to shed the offset in [s]
  float anim_speed = -1.0f;     // the clip's toe speed over the ground last frame [m/s] (< 0: none)
  // Releasing: the foot's own velocity over the ground (a pinned foot's rest, or a step's speed)
  // against the clip's, carried on and shed by a critically damped spring (inertialization), so
  // the drawn foot's velocity does not jump to the clip's [m], and its rate [m/s].
  glm::vec3 carry{0.0f};
  glm::vec3 carry_vel{0.0f};
};

struct FootLockInput {
  glm::vec3 anim_toe{0.0f};        // the clip's toe this frame, placed in the world [m]
  glm::vec3 anim_toe_prev{0.0f};   // the clip's toe last frame [m]
  glm::vec3 drawn_toe_prev{0.0f};  // the toe as drawn last frame [m]
  bool fresh = false;              // the agent's first frame: nothing carries over
  bool plant = false;              // the clips put this foot on the ground (a lock may start)
  bool hold = false;               // the clips still have weight on it (a lock is kept)
  float swing_progress = 0.0f;     // the clips' swing of this foot, 0 at lift-off, 1 at landing
  // The other foot is pinned (one foot steps at a time; a planted foot is pinned at once when the
  // other is not: it carries the weight).
  bool other_locked = false;
  // The gait clips are walking (they vote the feet): this foot's own swing comes soon and carries
  // it back to the clip's foot, so a drift alone starts no re-planting step (a step would lift it
  // while the other foot may still be rolling down onto its ball: both off the ground).
  bool walking = false;
  // The standing clips vote the feet (the gait clips and any start or stop carry less than
  // kGaitVoteWeight of the blend: a pedestrian creeping, or coming to rest). Their "both feet
  // down" is where a pinned toe stands: on the floor where they have it (stand_toe_y, never below
  // the floor), not raised with what the gait clips' swing adds to the blend (nor the height the
  // blend gives back to a stepping foot). A pinned toe rises with the clips' only while the clips
  // that step the feet vote them: then it is a push-off.
  bool standing_votes = false;
  float stand_toe_y = 0.0f;  // where the standing clips have this toe [m]
  // The body runs (clips with a flight phase, no double support, at or above the walk-run speed;
  // pose synthesis sets it): the foot pushes off on its toes into the air, not onto the other
  // foot, and a pinned ball follows the clips' up as well as down all through the stance (held
  // down while the clips rose, it was snatched up at the release: tried, gated to the push-off
  // alone, the CMU run's slide and pops came back).
  bool flight = false;
  // The other foot is in the air and coming down (walking: in the clips and not pinned yet; or in
  // a re-planting step), or pinned on its heel and still rolling down onto its ball: this one
  // keeps its weight (its lock) until the other has taken it over, as a trailing foot stays down
  // until the leading one is flat. (Running has a flight phase: no such wait.)
  bool other_landing = false;
  // The other foot is pinned on its heel (toe up, rolling down onto its ball), walking or not: it
  // has only just landed, and the body is not over it yet. This one starts no re-planting step
  // until it is flat: a trailing foot that leaves the floor while the leading one is on its heel
  // leaves the body on one heel, both toes in the air.
  bool other_on_heel = false;
  float floor_toe_m = 0.0f;  // where planted toes are (library floor) [m]
  // A ball this slow over the ground is at rest (clip analysis's "still": half the travel speed,
  // at least its capture-jitter floor) [m/s]. A plant pins the foot once its ball is at rest, or
  // once it has stopped slowing down: at its slowest, so the drawn foot stops with no jolt.
  float still_speed_m_s = 0.0f;
  // The clips' own ball speed over the ground [m/s] (< 0: not known). A ball at rest in the clips
  // has landed, though the drawn foot may still move with a blend's changing weights: it is
  // pinned then, if no faster over the ground than twice still_speed_m_s (the body's own speed,
  // or the still speed's capture-jitter floor's double for a slow body), not carried along the
  // floor until the weights settle.
  float clip_speed_m_s = -1.0f;
};

struct FootLockParams {
  // [s] halflife of a landing foot's offset; a release sheds its offset in no less than twice it
  float release_halflife_s = 0.06f;
  float step_distance_m = 0.25f;  // [m] a pinned foot this far from the clip's re-plants
  float step_time_s = 0.35f;      // [s] duration of a re-planting step
  float step_height_m = 0.05f;    // [m] its height (the clips' own swing)
  // [m/s] the clips' own peak swing speed: a released foot is never carried faster than this
  // toward the clip's foot (a long offset takes longer to shed; <= 0: no limit).
  float swing_speed_m_s = 0.0f;
  // [s] halflife of a released foot's carried velocity (its rest, or a step's speed, against the
  // clip's): the lock's whole release time, so the foot picks up the clip's swing over it.
  float carry_halflife_s = 0.12f;
  // [s] halflife of the glide of a foot pinned while it still moves over the ground (it takes the
  // weight as the other foot leaves it): its speed then falls from what it was, not to zero in a
  // frame. Half the landing offset's: loaded, it stops faster than a settling foot.
  float glide_halflife_s = 0.03f;
};

// One frame of one foot: its next state and where its toe should be drawn (world, before any
// pelvis drop and floor clamp; the caller applies both).
struct FootLockStep {
  FootLock state;
  glm::vec3 goal{0.0f};
};

// Advances one foot by dt_s [s]: the state's transition for this input (plant, release, step), then
// where the foot is drawn in its new state. Unusable input (NaN, infinities, coordinates beyond
// 1e6 m, a dt_s that is not a finite positive number) never reaches the state: without a usable
// clip toe or time step the foot keeps its state and its last goal (a fresh one is a default
// FootLock drawn at the origin); an unusable previous toe counts as the clip's toe this frame, an
// unusable floor as none, an unusable standing clips' toe as the floor, an unusable swing progress
// or still speed as 0.
FootLockStep step_foot_lock(const FootLock& state, const FootLockInput& in,
                            const FootLockParams& params, float dt_s);

// step_foot_lock with the state advanced where it is stored: the same state and goal, without
// copying the state in and out (pose synthesis runs it for every foot each frame).
glm::vec3 advance_foot_lock(FootLock& state, const FootLockInput& in, const FootLockParams& params,
                            float dt_s);

// A new agent's foot: unlocked, drawn at the clip's toe (no offset, no speed).
FootLock fresh_foot_lock(const glm::vec3& anim_toe);

// Pins the foot where it was drawn last frame (the clip's toe on a fresh frame), no higher than
// drawn nor than the clip has it and never below the floor; as far as it was drawn above the
// clip's toe last frame, it settles onto the pin through the offset. Expects usable input
// (step_foot_lock replaces what is not).
FootLock plant_foot(const FootLock& state, const FootLockInput& in);

// Starts a re-planting step of a pinned foot from where it is drawn (from): used when the leg
// cannot reach where it is pinned while the clips still have the foot on the ground. An unusable
// `from` starts from the last goal.
FootLock start_foot_step(const FootLock& state, const glm::vec3& from);

// Lets a pinned or stepping foot go from where it is drawn (drawn_toe, moving at drawn_vel) to the
// clip's toe (anim_toe, moving at anim_vel) through an inertialization offset: the offset is shed
// over the swing, and the horizontal velocity difference drawn_vel - anim_vel is carried on and
// shed (`carry`), so the drawn foot keeps its own speed at first. Pass the clip's toe of the frame
// the foot was last drawn, so that this frame moves on from there. Unusable values count as: the
// last goal for drawn_toe, drawn_toe for anim_toe, no speed for the velocities.
FootLock release_foot_lock(const FootLock& state, const glm::vec3& drawn_toe,
                           const glm::vec3& drawn_vel, const glm::vec3& anim_toe,
                           const glm::vec3& anim_vel);

}  // namespace gk
