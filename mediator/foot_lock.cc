#include "mediator/foot_lock.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <glm/common.hpp>

#include "mediator/springs.h"

namespace gk {
namespace {

// Share of a re-planting step spent lifting the foot before it moves (and setting it down after).
constexpr float kStepLift = 0.2f;
// [m] Coordinates beyond this are garbage, not a place (as the mediator's input check).
constexpr float kMaxCoordinate = 1e6f;

bool usable(float x) { return std::isfinite(x) && std::abs(x) <= kMaxCoordinate; }
bool usable(const glm::vec3& v) { return usable(v.x) && usable(v.y) && usable(v.z); }

// True when step_foot_lock has some input value to replace (sanitise).
bool needs_sanitising(const FootLockInput& in) {
  return !usable(in.anim_toe_prev) || !usable(in.drawn_toe_prev) || !usable(in.floor_toe_m) ||
         !usable(in.stand_toe_y) || !std::isfinite(in.swing_progress) ||
         !std::isfinite(in.still_speed_m_s);
}

// The input with unusable values replaced as step_foot_lock documents (anim_toe is usable).
void sanitise(FootLockInput& out) {
  if (!usable(out.anim_toe_prev)) out.anim_toe_prev = out.anim_toe;
  if (!usable(out.drawn_toe_prev)) out.drawn_toe_prev = out.anim_toe;
  if (!usable(out.floor_toe_m)) out.floor_toe_m = std::numeric_limits<float>::lowest();
  if (!usable(out.stand_toe_y)) {
    out.stand_toe_y = usable(out.floor_toe_m) ? out.floor_toe_m : out.anim_toe.y;
  }
  if (!std::isfinite(out.swing_progress)) out.swing_progress = 0.0f;
  if (!std::isfinite(out.still_speed_m_s)) out.still_speed_m_s = 0.0f;
}

// The transitions and the per-state steps below change one FootLock in place: the state is some
// 150 bytes, and a copy per function (each written field by field, then read back whole) cost
// more than the arithmetic. The public functions at the end keep their value form.

// A pinned toe follows the clip's toe down onto the floor as the foot rolls from the heel onto
// the ball. It rises with the clip's while the other foot is pinned: that one carries the weight,
// and this one pivots onto its toes to push off; and in a run, whose push-off is on the toes too,
// into the air (held down until the clips let it go, the ball was then snatched up centimetres in
// a frame or two, snapping the knee). Alone on the ground in a walk, the ball bears the weight and
// stays down (the heel rises about it). It rises as fast as the clip's does this frame;
// what it has to catch up beyond that (the clip's toe already higher when the other foot is
// pinned) goes through the settling offset, so the drawn toe never jumps. While the standing clips
// vote the feet (a creeping pedestrian) the pin stands where they have the toe, and a pin above
// that (a push-off the gait clips began) comes down to it through the settling offset as well.
void pin_height(FootLock& s, const FootLockInput& in) {
  const float clip_y = std::max(in.floor_toe_m, in.anim_toe.y);
  if (((in.other_locked && !in.standing_votes) || in.flight) && clip_y > s.target.y) {
    const float clip_rise = std::max(0.0f, in.anim_toe.y - in.anim_toe_prev.y);
    s.offset.y -= std::max(0.0f, clip_y - s.target.y - clip_rise);
    s.target.y = clip_y;
    return;
  }
  // (No higher than the clip's toe: below the standing clips' toe, the pin follows it down as it
  // would otherwise; lowered only to their toe, it then dropped to the clip's in a frame.)
  const float stand_y = std::min(std::max(in.floor_toe_m, in.stand_toe_y), clip_y);
  if (in.standing_votes && s.target.y > stand_y) {
    s.offset.y += s.target.y - stand_y;
    s.target.y = stand_y;
    return;
  }
  s.target.y = std::min(s.target.y, clip_y);
}

// The offset of a foot that is not being released decays toward zero (Holden's decay spring:
// exact for any dt).
void decay_offset(FootLock& s, const FootLockParams& p, float dt) {
  const float halflife = s.offset_halflife_s > 0.0f ? s.offset_halflife_s : p.release_halflife_s;
  critical_spring(s.offset, s.offset_vel, glm::vec3(0.0f), halflife, dt);
}

void plant(FootLock& s, const FootLockInput& in) {
  // Pinned no higher than it is drawn (a pinned toe never rises) nor than the clip has it, and
  // never below the floor; a foot drawn above the clip's toe settles down onto it. Above means
  // last frame's drawn toe against last frame's clip toe: the clip's toe may drop a centimetre or
  // more in the frame the foot lands (the ball slapping down off the heel), and a pin held at last
  // frame's height would lift the ankle by that much against a nearly straight leg, the knee
  // snapping bent.
  const glm::vec3 at = in.fresh ? in.anim_toe : in.drawn_toe_prev;
  const float drawn_y = at.y;
  const float y = std::max(in.floor_toe_m, std::min(drawn_y, in.anim_toe.y));
  s.state = FootLockState::kLocked;
  s.target = glm::vec3(at.x, y, at.z);
  float above = std::max(0.0f, drawn_y - y);
  if (!in.fresh) above = std::min(above, std::max(0.0f, in.drawn_toe_prev.y - in.anim_toe_prev.y));
  s.offset = glm::vec3(0.0f, above, 0.0f);
  s.offset_vel = glm::vec3(0.0f);
  s.offset_halflife_s = 0.0f;
}

// A foot pinned while it still moves over the ground at `moving` [m/s] glides to its pin: the pin
// is set where a critically damped spring of the glide's halflife, starting at that speed, comes
// to rest (moving / y ahead, y its damping over two), so the drawn foot's velocity is continuous
// and falls off exponentially, with no overshoot. Stopped in a frame instead, a foot landing at
// a run's swing speed snaps the ankle and knee (hundreds of m/s^2).
void glide_to_pin(FootLock& s, glm::vec3 moving, const FootLockParams& p) {
  const float halflife = std::max(p.glide_halflife_s, 1e-3f);
  const float y = 0.5f * halflife_to_damping(halflife);
  // No foot is carried faster than the clips' own swing (a velocity taken across a reset or a
  // teleport is not a foot's).
  const float speed = ground_length(moving.x, moving.z);
  if (p.swing_speed_m_s > 0.0f && speed > p.swing_speed_m_s) moving *= p.swing_speed_m_s / speed;
  const glm::vec3 ahead = moving / y;
  s.target += ahead;
  s.offset -= ahead;
  s.offset_vel = moving;
  s.offset_halflife_s = halflife;
}

// The vectors by value: callers pass fields of s itself.
void start_step(FootLock& s, glm::vec3 from) {
  s.state = FootLockState::kStepping;
  s.from = usable(from) ? from : s.last_goal;
  s.timer_s = 0.0f;
  s.offset = s.offset_vel = glm::vec3(0.0f);
  s.offset_halflife_s = 0.0f;  // the pin it sets down settles as a landing does
}

void release(FootLock& s, glm::vec3 drawn_toe, glm::vec3 drawn_vel, glm::vec3 anim_toe,
             glm::vec3 anim_vel) {
  const glm::vec3 drawn = usable(drawn_toe) ? drawn_toe : s.last_goal;
  const glm::vec3 anim = usable(anim_toe) ? anim_toe : drawn;
  const glm::vec3 dv = usable(drawn_vel) ? drawn_vel : glm::vec3(0.0f);
  const glm::vec3 av = usable(anim_vel) ? anim_vel : glm::vec3(0.0f);
  s.state = FootLockState::kReleasing;
  s.from = drawn;
  s.offset = drawn - anim;
  s.offset_vel = dv - av;
  s.carry = glm::vec3(0.0f);
  s.carry_vel = glm::vec3(s.offset_vel.x, 0.0f, s.offset_vel.z);
  s.shed = s.shed_from = s.shed_goal = s.released_s = s.release_time_s = 0.0f;
  s.offset_halflife_s = 0.0f;  // what is left of the release settles as a landing's offset
  s.swing_from = -1.0f;        // taken from the first frame's progress
}

// This frame's transition from the state the foot was in. speed and last_speed are the clip's toe
// speed over the ground this frame and last (< 0: none); dt the frame's time step [s] (> 0).
void transition(FootLock& s, const FootLockInput& in, const FootLockParams& p,
                const glm::vec3& anim_vel, float speed, float last_speed, float dt) {
  switch (s.state) {
    case FootLockState::kFree:
    case FootLockState::kReleasing: {
      // The clips plant the foot while its ball may still roll down and forward off the heel
      // (and a blend of clips lands a foot over a few frames): it is pinned once the ball has come
      // to rest over the ground, or has stopped slowing down, where it was drawn last frame (or
      // rests in the clips themselves, the blend's changing weights still carrying it on no faster
      // than twice the still speed, about the body's: a landed foot, not a swing to finish); and
      // at once if the other foot is not pinned: off the ground, it leaves this one the weight,
      // and a foot that carries the weight does not move over the ground.
      const bool clip_at_rest = in.clip_speed_m_s >= 0.0f &&
                                in.clip_speed_m_s <= in.still_speed_m_s &&
                                speed <= 2.0f * in.still_speed_m_s;
      const bool at_rest = in.fresh || speed <= in.still_speed_m_s || clip_at_rest ||
                           (last_speed >= 0.0f && speed >= last_speed);
      const bool carries_weight = !in.other_locked;
      if (in.plant && (at_rest || carries_weight)) {
        // The drawn foot's velocity over the ground last frame (the goal's). It glides to its pin
        // when pinned before it is at rest, and when it is drawn moving over the ground faster
        // than the clip's ball by more than the body's own speed (twice the still speed), as a
        // released foot still shedding its offset is while its ball in the clips has landed.
        const glm::vec3 moving(s.goal_vel.x, 0.0f, s.goal_vel.z);
        const bool carried = ground_length(moving.x, moving.z) > speed + 2.0f * in.still_speed_m_s;
        plant(s, in);
        if ((!at_rest || carried) && !in.fresh && usable(moving)) glide_to_pin(s, moving, p);
      }
      return;
    }
    case FootLockState::kLocked: {
      if (!in.hold && !in.other_landing) {
        // Released from rest: the offset is taken against where the clip's toe was last frame,
        // and the foot's rest against the clip's speed is carried on and shed (inertialization),
        // so the drawn foot sets off from rest: taking the clip's lift-off speed at once, the
        // knee of a leg stretched to its pin would snap. A pin that rises with the clip's toe
        // (pin_height: a run's ball rising into the push-off) is taken as it was last frame too,
        // and sets off at the speed it was rising: raised to this frame's height first, it then
        // rose by the clip's rise once more, twice the clip's in the release's frame (a ball
        // snatched up 4 cm in a frame at a run's push-off).
        const glm::vec3 was = s.target + s.offset;
        pin_height(s, in);
        glm::vec3 drawn = s.target + s.offset;
        const float rise = std::max(0.0f, drawn.y - was.y);
        drawn.y = std::min(drawn.y, was.y);
        release(s, drawn, glm::vec3(0.0f, rise / dt, 0.0f), in.anim_toe_prev, anim_vel);
        return;
      }
      // A foot left behind by a turn or a drift while the clips stand re-plants with a short step,
      // one foot at a time, once the other is flat on the floor (walking, its own swing comes and
      // takes the offset).
      const float drift = ground_length(s.target.x - in.anim_toe.x, s.target.z - in.anim_toe.z);
      if (drift > p.step_distance_m && in.other_locked && !in.other_on_heel && !in.walking) {
        pin_height(s, in);
        start_step(s, s.target + s.offset);
      }
      // Otherwise the pin is kept as it is (pinned_foot lowers it below).
      return;
    }
    case FootLockState::kStepping: {
      // The clips lift the foot before the step is done: it joins their swing from where it is,
      // at the speed it has.
      if (in.hold) return;
      // The offset is taken against where the clip's toe was when the step was last drawn: this
      // frame the drawn foot then moves on with the step's own velocity (carried on), not
      // with that less the clip's (a jolt of a frame, as the clip's foot is lifting fast).
      release(s, s.last_goal, s.goal_vel, in.anim_toe_prev, anim_vel);
      return;
    }
  }
}

// A free foot is drawn at the clip's toe plus what is left of a landing offset.
glm::vec3 free_foot(const FootLock& s, const FootLockInput& in) { return in.anim_toe + s.offset; }

// A pinned foot is drawn at its pin (lowered onto the clip's toe) plus the settling offset.
glm::vec3 pinned_foot(FootLock& s, const FootLockInput& in) {
  pin_height(s, in);
  return s.target + s.offset;
}

// A released foot sheds its offset in the swing's progress from where the release began, and
// never in less than twice the halflife; done, it is free.
glm::vec3 releasing_foot(FootLock& s, const FootLockInput& in, const FootLockParams& p, float dt) {
  if (s.swing_from < 0.0f) {
    // The release's shortest time: twice the halflife, and long enough that the foot is never
    // carried faster than the clips' own swing (smoothstep's speed peaks at 1.5 times its mean).
    const float across = ground_length(s.offset.x, s.offset.z);
    s.release_time_s = 2.0f * p.release_halflife_s;
    if (p.swing_speed_m_s > 0.0f) {
      s.release_time_s = std::max(s.release_time_s, 1.5f * across / p.swing_speed_m_s);
    }
  }
  // A progress that went back, or leapt forward by more than a swing advances in a frame, as when
  // the blend changes clips, restarts the count from there: never a jump.
  const bool leapt = s.swing_from >= 0.0f && in.swing_progress > s.last_progress + 0.25f;
  if (s.swing_from < 0.0f || in.swing_progress + 0.05f < s.swing_from || leapt) {
    s.swing_from = std::min(in.swing_progress, 0.9f);
    s.shed_from = s.shed_goal;
  }
  s.last_progress = in.swing_progress;
  const float u = (in.swing_progress - s.swing_from) / (1.0f - s.swing_from);
  s.shed_goal = std::max(s.shed_goal, s.shed_from + (1.0f - s.shed_from) * smoothstep01(u));
  // A release late in the swing still takes its time (twice the halflife at least), not a frame
  // or two; it may then land before the offset is gone, and is pinned where it is.
  s.released_s += dt;
  const float by_time = smoothstep01(s.released_s / s.release_time_s);
  s.shed = std::max(s.shed, std::min(s.shed_goal, by_time));
  // Upward the foot follows the clip's lift at once (a spring, so the knee does not snap);
  // sideways it is corrected over the swing. A foot released above the clip's (a re-planting
  // step the clips lift) comes down to it over the swing as well: pulled down at once, the knee
  // would snap straight.
  const bool above = s.offset.y > 0.0f;
  if (!above) {
    float y = s.offset.y, vy = s.offset_vel.y;
    critical_spring(y, vy, 0.0f, 0.5f * p.release_halflife_s, dt);
    s.offset.y = y;
    s.offset_vel.y = vy;
  }
  critical_spring(s.carry, s.carry_vel, glm::vec3(0.0f), p.carry_halflife_s, dt);
  glm::vec3 goal = in.anim_toe + s.offset * (1.0f - s.shed) + s.carry;
  goal.y = in.anim_toe.y + (above ? s.offset.y * (1.0f - s.shed) : s.offset.y);
  if (s.shed >= 1.0f) {
    // Free; what is left of a carried velocity goes on decaying as the free foot's offset, so the
    // foot joins the clip's without a jump.
    s.state = FootLockState::kFree;
    s.offset = s.carry;
    s.offset_vel = s.carry_vel;
    s.carry = s.carry_vel = glm::vec3(0.0f);
  }
  return goal;
}

// A re-planting step: lifted, carried and set down on the floor where the clip has the foot, as
// high as the clips' own swing: the foot rises before it moves and stops moving before it lands
// (zero speed at both ends, so nothing snaps). Landed, it is pinned there.
glm::vec3 stepping_foot(FootLock& s, const FootLockInput& in, const FootLockParams& p, float dt) {
  const bool first = s.timer_s <= 0.0f;
  s.timer_s += dt;
  const float u = std::min(1.0f, s.timer_s / p.step_time_s);
  const float sn = std::sin(std::numbers::pi_v<float> * u);
  // It is set down on the floor (where the standing clips have the toe, while they vote the
  // feet), never at the blend's toe height: that is the walk's share swinging the foot, and a step
  // set down there was pinned in the air.
  float land_y = in.standing_votes ? in.stand_toe_y : in.floor_toe_m;
  if (!usable(land_y)) land_y = in.anim_toe.y;  // no floor known: where the clip has the toe
  glm::vec3 to(in.anim_toe.x, std::max(in.floor_toe_m, land_y), in.anim_toe.z);
  // Where it lands is chosen before it comes down: it follows the clip's foot while it is
  // carried, and is set down on the spot it was carried to (a body turning on the spot would
  // otherwise drag the landing foot along the ground). Where the clip's foot jumps (a blend
  // changing under it: a walk fading in moves it back by centimetres a frame) it is followed on a
  // critically damped spring of a glide's halflife: a step aimed at it directly reversed in a
  // frame, snapping the ankle.
  if (first) {
    s.step_to = glm::vec3(to.x, 0.0f, to.z);
    s.step_to_vel = glm::vec3(0.0f);
  } else if (u < 1.0f - kStepLift) {
    // The clip's foot carried with the body (no faster than twice the still speed, the body's own)
    // is followed as it goes; what it moves beyond that, a blend changing, on the spring.
    glm::vec3 carried(in.anim_toe.x - in.anim_toe_prev.x, 0.0f, in.anim_toe.z - in.anim_toe_prev.z);
    const float most = 2.0f * in.still_speed_m_s * dt, len = glm::length(carried);
    if (len > most) carried *= most / len;
    s.step_to += carried;
    critical_spring(s.step_to, s.step_to_vel, glm::vec3(to.x, 0.0f, to.z), p.glide_halflife_s, dt);
  }
  to.x = s.step_to.x;
  to.z = s.step_to.z;
  glm::vec3 goal = glm::mix(s.from, to, smoothstep01((u - kStepLift) / (1.0f - 2.0f * kStepLift)));
  goal.y = glm::mix(s.from.y, to.y, smoothstep01(u)) + p.step_height_m * sn * sn;
  if (u >= 1.0f) {
    s.state = FootLockState::kLocked;
    s.target = to;
  }
  return goal;
}

}  // namespace

FootLock fresh_foot_lock(const glm::vec3& anim_toe) {
  FootLock s;
  s.last_goal = anim_toe;
  return s;
}

FootLock plant_foot(const FootLock& s, const FootLockInput& in) {
  FootLock out = s;
  plant(out, in);
  return out;
}

FootLock start_foot_step(const FootLock& s, const glm::vec3& from) {
  FootLock out = s;
  start_step(out, from);
  return out;
}

FootLock release_foot_lock(const FootLock& s, const glm::vec3& drawn_toe,
                           const glm::vec3& drawn_vel, const glm::vec3& anim_toe,
                           const glm::vec3& anim_vel) {
  FootLock out = s;
  release(out, drawn_toe, drawn_vel, anim_toe, anim_vel);
  return out;
}

glm::vec3 advance_foot_lock(FootLock& s, const FootLockInput& raw, const FootLockParams& p,
                            float dt) {
  // Nothing to follow or no time step: the foot stays as it is (a fresh one at the origin).
  if (!usable(raw.anim_toe) || !(dt > 0.0f) || !std::isfinite(dt)) {
    if (raw.fresh) s = FootLock();
    return s.last_goal;
  }
  // Almost every input is usable as it is: it is read in place, not copied.
  FootLockInput fixed;
  const FootLockInput* use = &raw;
  if (needs_sanitising(raw)) {
    fixed = raw;
    sanitise(fixed);
    use = &fixed;
  }
  const FootLockInput& in = *use;
  if (in.fresh) s = fresh_foot_lock(in.anim_toe);
  const glm::vec3 anim_vel = in.fresh ? glm::vec3(0.0f) : (in.anim_toe - in.anim_toe_prev) / dt;
  // The clip's toe speed over the ground, this frame and last (< 0: none yet).
  const float speed = ground_length(anim_vel.x, anim_vel.z);
  const float last_speed = s.anim_speed;
  s.anim_speed = in.fresh ? -1.0f : speed;

  transition(s, in, p, anim_vel, speed, last_speed, dt);
  if (s.state != FootLockState::kReleasing) decay_offset(s, p, dt);
  glm::vec3 goal = in.anim_toe;
  switch (s.state) {
    case FootLockState::kFree:
      goal = free_foot(s, in);
      break;
    case FootLockState::kLocked:
      goal = pinned_foot(s, in);
      break;
    case FootLockState::kReleasing:
      goal = releasing_foot(s, in, p, dt);
      break;
    case FootLockState::kStepping:
      goal = stepping_foot(s, in, p, dt);
      break;
  }
  s.goal_vel = in.fresh ? glm::vec3(0.0f) : (goal - s.last_goal) / dt;
  s.last_goal = goal;
  return goal;
}

FootLockStep step_foot_lock(const FootLock& state, const FootLockInput& in, const FootLockParams& p,
                            float dt) {
  FootLockStep next{state, glm::vec3(0.0f)};
  next.goal = advance_foot_lock(next.state, in, p, dt);
  return next;
}

}  // namespace gk
