#include "mediator/foot_lock.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/common.hpp>

#include "mediator/springs.h"

namespace gk {
namespace {

// Share of a re-planting step spent lifting the foot before it moves (and setting it down after).
constexpr float kStepLift = 0.2f;

// Decays an inertialization offset toward zero (Holden's decay spring: exact for any dt).
void decay_offset(glm::vec3& x, glm::vec3& v, float halflife_s, float dt) {
  critical_spring(x, v, glm::vec3(0.0f), halflife_s, dt);
}

}  // namespace

void release_foot_lock(FootLock& lock, const glm::vec3& drawn_toe, const glm::vec3& drawn_vel,
                       const glm::vec3& anim_toe, const glm::vec3& anim_vel) {
  lock.state = FootLockState::kReleasing;
  lock.from = drawn_toe;
  lock.offset = drawn_toe - anim_toe;
  lock.offset_vel = drawn_vel - anim_vel;

  lock.shed = lock.shed_from = lock.shed_goal = lock.released_s = lock.release_time_s = 0.0f;
  lock.swing_from = -1.0f;  // taken from the first frame's progress
}

void start_foot_step(FootLock& lock, const glm::vec3& from) {
  lock.state = FootLockState::kStepping;
  lock.from = from;
  lock.timer_s = 0.0f;
  lock.offset = lock.offset_vel = glm::vec3(0.0f);
}

namespace {

glm::vec3 advance(FootLock& lock, const FootLockInput& in, const FootLockParams& p, float dt) {
  const glm::vec3 anim_vel = in.fresh ? glm::vec3(0.0f) : (in.anim_toe - in.anim_toe_prev) / dt;
  // The clip's toe speed over the ground, this frame and last (< 0: none yet).
  const float speed = std::hypot(anim_vel.x, anim_vel.z);
  const float last_speed = lock.anim_speed;
  lock.anim_speed = in.fresh ? -1.0f : speed;
  auto lock_here = [&](const glm::vec3& at) {
    lock.state = FootLockState::kLocked;
    // Pinned no higher than it is drawn (a pinned toe never rises) nor than the clip has it, and
    // never below the floor; a foot drawn above that settles down onto it.
    const float drawn_y = in.fresh ? in.anim_toe.y : in.drawn_toe_prev.y;
    const float y = std::max(in.floor_toe_m, std::min(drawn_y, in.anim_toe.y));
    lock.target = glm::vec3(at.x, y, at.z);
    lock.offset = glm::vec3(0.0f, std::max(0.0f, drawn_y - y), 0.0f);
    lock.offset_vel = glm::vec3(0.0f);
  };
  // Where the toe is drawn while pinned: it follows the clip's toe down onto the floor as the foot
  // rolls from the heel onto the ball, and never up again while the ball bears weight (the heel
  // rises about it); the clips lifting it ends the lock.
  auto pinned_goal = [&] {
    lock.target.y = std::min(lock.target.y, std::max(in.floor_toe_m, in.anim_toe.y));
    return lock.target;
  };

  switch (lock.state) {
    case FootLockState::kFree:
    case FootLockState::kReleasing: {
      // The clips plant the foot while its ball may still roll down and forward off the heel
      // (and a blend of clips lands a foot over a few frames): it is pinned once the ball has come
      // to rest over the ground, or has stopped slowing down, where it was drawn last frame.
      const bool at_rest = in.fresh || speed <= in.still_speed_m_s ||
                           (last_speed >= 0.0f && speed >= last_speed);
      if (in.plant && at_rest) lock_here(in.fresh ? in.anim_toe : in.drawn_toe_prev);
      break;
    }
    case FootLockState::kLocked: {
      if (!in.hold && !in.other_landing) {
        release_foot_lock(lock, pinned_goal() + lock.offset, glm::vec3(0.0f), in.anim_toe,
                          anim_vel);
        break;
      }
      // A foot left behind by a turn or a drift re-plants with a short step, one foot at a time.
      const float drift = std::hypot(lock.target.x - in.anim_toe.x, lock.target.z - in.anim_toe.z);
      if (drift > p.step_distance_m && in.other_locked)
        start_foot_step(lock, pinned_goal() + lock.offset);
      break;
    }
    case FootLockState::kStepping:
      // The clips lift the foot before the step is done: it joins their swing from where it is,
      // at the speed it has.
      if (!in.hold) release_foot_lock(lock, lock.last_goal, lock.goal_vel, in.anim_toe, anim_vel);
      break;
  }

  if (lock.state != FootLockState::kReleasing) {
    decay_offset(lock.offset, lock.offset_vel, p.release_halflife_s, dt);
  }
  switch (lock.state) {
    case FootLockState::kFree:
      return in.anim_toe + lock.offset;
    case FootLockState::kReleasing: {
      // Shed in the swing's progress from where the release began (a progress that went back,
      // as when the blend changes clips, restarts the count from there: never a jump).
      if (lock.swing_from < 0.0f) {
        // Smoothstep's speed peaks at 1.5 times its mean: at the clips' swing speed at most.
        const float across = std::hypot(lock.offset.x, lock.offset.z);
        lock.release_time_s = 2.0f * p.release_halflife_s;
        if (p.swing_speed_m_s > 0.0f) {
          lock.release_time_s = std::max(lock.release_time_s, 1.5f * across / p.swing_speed_m_s);
        }
      }
      if (lock.swing_from < 0.0f || in.swing_progress + 0.05f < lock.swing_from) {
        lock.swing_from = std::min(in.swing_progress, 0.9f);
        lock.shed_from = lock.shed_goal;
      }
      const float u = (in.swing_progress - lock.swing_from) / (1.0f - lock.swing_from);
      lock.shed_goal =
          std::max(lock.shed_goal, lock.shed_from + (1.0f - lock.shed_from) * smoothstep01(u));
      // A release late in the swing still takes its time (twice the halflife at least), not a
      // frame or two; it may then land before the offset is gone, and is pinned where it is.
      lock.released_s += dt;
      const float by_time = smoothstep01(lock.released_s / lock.release_time_s);
      lock.shed = std::max(lock.shed, std::min(lock.shed_goal, by_time));
      // Upward the foot follows the clip's lift at once (a spring, so the knee does not snap);
      // sideways it is corrected over the swing.
      {
        float y = lock.offset.y, vy = lock.offset_vel.y;
        critical_spring(y, vy, 0.0f, 0.5f * p.release_halflife_s, dt);
        lock.offset.y = y;
        lock.offset_vel.y = vy;
      }
      glm::vec3 goal = in.anim_toe + lock.offset * (1.0f - lock.shed);
      goal.y = in.anim_toe.y + lock.offset.y;
      if (lock.shed >= 1.0f) {
        lock.state = FootLockState::kFree;
        lock.offset = lock.offset_vel = glm::vec3(0.0f);
      }
      return goal;
    }
    case FootLockState::kLocked:
      return pinned_goal() + lock.offset;
    case FootLockState::kStepping: {
      // Lifted, carried and set down where the clip has the foot, as high as the clips' own
      // swing: the foot rises before it moves and stops moving before it lands (zero speed at
      // both ends, so nothing snaps).
      lock.timer_s += dt;
      const float u = std::min(1.0f, lock.timer_s / p.step_time_s);
      const float s = std::sin(std::numbers::pi_v<float> * u);
      glm::vec3 to(in.anim_toe.x, std::max(in.floor_toe_m, in.anim_toe.y), in.anim_toe.z);
      // Where it lands is chosen before it comes down: it follows the clip's foot while it is
      // carried, and is set down on the spot it was carried to (a body turning on the spot would
      // otherwise drag the landing foot along the ground).
      if (u < 1.0f - kStepLift) {
        lock.step_to = to;
      } else {
        to.x = lock.step_to.x;
        to.z = lock.step_to.z;
      }
      glm::vec3 goal =
          glm::mix(lock.from, to, smoothstep01((u - kStepLift) / (1.0f - 2.0f * kStepLift)));
      goal.y = glm::mix(lock.from.y, to.y, smoothstep01(u)) + p.step_height_m * s * s;
      if (u >= 1.0f) {
        lock.state = FootLockState::kLocked;
        lock.target = to;
      }
      return goal;
    }
  }
  return in.anim_toe;
}

}  // namespace

glm::vec3 step_foot_lock(FootLock& lock, const FootLockInput& in, const FootLockParams& p,
                         float dt) {
  if (in.fresh) {
    lock = FootLock();
    lock.last_goal = in.anim_toe;
  }
  const glm::vec3 goal = advance(lock, in, p, dt);
  lock.goal_vel = in.fresh ? glm::vec3(0.0f) : (goal - lock.last_goal) / dt;
  lock.last_goal = goal;
  return goal;
}

}  // namespace gk
