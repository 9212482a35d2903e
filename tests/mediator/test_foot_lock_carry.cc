// Two limits of the foot lock that keep a foot from being dragged (mediator/foot_lock): a
// re-planting step sets the foot down where it has carried it, and a released foot is never
// carried toward the clip's foot faster than the clips' own swing.

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "mediator/foot_lock.h"

namespace gk {
namespace {

constexpr float kDt = 1.0f / 60.0f;
constexpr float kFloor = 0.02f;

float horizontal(const glm::vec3& a, const glm::vec3& b) {
  return std::hypot(a.x - b.x, a.z - b.z);
}

// One frame of the pure state machine: the lock advances in place, the goal is returned.
glm::vec3 advance(FootLock& lock, const FootLockInput& in, const FootLockParams& p) {
  const FootLockStep r = step_foot_lock(lock, in, p, kDt);
  lock = r.state;
  return r.goal;
}

FootLockInput input(const glm::vec3& anim, const glm::vec3& anim_prev, const glm::vec3& drawn_prev,
                    bool plant, bool hold, float progress) {
  FootLockInput in;
  in.anim_toe = anim;
  in.anim_toe_prev = anim_prev;
  in.drawn_toe_prev = drawn_prev;
  in.plant = plant;
  in.hold = hold;
  in.swing_progress = progress;
  in.floor_toe_m = kFloor;
  return in;
}

// A body turning on the spot carries the clip's toe sideways at 1.5 m/s through a whole
// re-planting step: the foot follows it while carried, and comes down on one spot.
TEST(FootLockCarry, StepSetsTheFootDownWhereItWasCarried) {
  FootLockParams p;
  FootLock lock;
  glm::vec3 anim(0.0f, kFloor, 0.0f);
  FootLockInput in = input(anim, anim, anim, true, true, 0.0f);
  in.fresh = true;
  glm::vec3 goal = advance(lock, in, p);
  ASSERT_EQ(lock.state, FootLockState::kLocked);
  lock = start_foot_step(lock, goal);
  const float speed = 1.5f;  // [m/s] of the clip's toe
  int lowering = 0;
  glm::vec3 set_down(0.0f);
  for (int k = 1; k <= 40 && lock.state == FootLockState::kStepping; ++k) {
    const glm::vec3 prev_anim = anim, prev_goal = goal;
    anim.x += speed * kDt;
    goal = advance(lock, input(anim, prev_anim, prev_goal, false, true, 0.0f), p);
    const float t = k * kDt;
    if (t >= (1.0f - 0.2f) * p.step_time_s + kDt) {
      // The last fifth only sets the foot down: no horizontal motion at all.
      if (lowering++ == 0) set_down = prev_goal;
      EXPECT_NEAR(horizontal(goal, set_down), 0.0f, 1e-6f) << k;
    }
  }
  ASSERT_EQ(lock.state, FootLockState::kLocked);
  EXPECT_GE(lowering, 3);
  // It came down where it was carried to, behind the clip's toe, which moved on.
  EXPECT_GT(horizontal(anim, goal), 0.05f);
  // Pinned there on the next frame.
  const glm::vec3 prev_anim = anim;
  anim.x += speed * kDt;
  const glm::vec3 pinned =
      advance(lock, input(anim, prev_anim, goal, false, true, 0.0f), p);
  EXPECT_NEAR(horizontal(pinned, goal), 0.0f, 1e-6f);
}

// Released 0.75 m from a clip toe that stands still (a foot left behind in a jam): with the
// clips' swing speed given, the foot is carried at no more than that speed; without it, the
// release's shortest time (twice the halflife) would carry it at several times that.
TEST(FootLockCarry, ReleasedFootIsCarriedNoFasterThanTheClipsSwing) {
  for (const float swing_speed : {0.0f, 3.0f}) {
    FootLockParams p;
    p.swing_speed_m_s = swing_speed;
    FootLock lock;
    const glm::vec3 pinned(0.0f, kFloor, 0.0f), anim(0.75f, kFloor, 0.0f);
    FootLockInput in = input(pinned, pinned, pinned, true, true, 0.0f);
    in.fresh = true;
    glm::vec3 goal = advance(lock, in, p);
    lock = release_foot_lock(lock, goal, glm::vec3(0.0f), anim, glm::vec3(0.0f));
    float fastest = 0.0f;
    int frames = 0;
    for (int k = 1; k <= 120 && lock.state == FootLockState::kReleasing; ++k, ++frames) {
      const glm::vec3 prev = goal;
      // A short swing of the clips (0.1 s, as at a crawl in a jam); their toe stays put.
      goal = advance(lock, input(anim, anim, prev, false, false, std::min(1.0f, k / 6.0f)), p);
      fastest = std::max(fastest, horizontal(goal, prev) / kDt);
    }
    EXPECT_NEAR(horizontal(goal, anim), 0.0f, 1e-4f);
    if (swing_speed > 0.0f) {
      EXPECT_LE(fastest, swing_speed * 1.02f);
      // 0.75 m at a smoothstep peaking at 3 m/s takes 1.5 * 0.75 / 3 = 0.375 s.
      EXPECT_GE(frames, static_cast<int>(0.375f / kDt) - 1);
    } else {
      EXPECT_GT(fastest, 6.0f) << "the unlimited release is fast: the test would catch a drag";
    }
  }
}

}  // namespace
}  // namespace gk
