// The foot-lock transitions one at a time (mediator/foot_lock.h): a given state and input, and the
// state and goal derived by hand from what the header promises. Expected values are worked out
// here in double precision from the formulas named in each test, never read back from the code.

#include <algorithm>
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "mediator/foot_lock.h"
#include "mediator/springs.h"

namespace gk {
namespace {

constexpr float kDt = 1.0f / 60.0f;
constexpr float kFloor = 0.02f;
const float kNaN = std::numeric_limits<float>::quiet_NaN();

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Every number of the state is finite and the state is one of the four.
void expect_defined(const FootLock& s, const char* what) {
  EXPECT_TRUE(s.state == FootLockState::kFree || s.state == FootLockState::kLocked ||
              s.state == FootLockState::kReleasing || s.state == FootLockState::kStepping)
      << what;
  for (const glm::vec3& v :
       {s.target, s.offset, s.offset_vel, s.from, s.last_goal, s.goal_vel, s.carry, s.carry_vel}) {
    EXPECT_TRUE(finite(v)) << what;
  }
  for (float x :
       {s.timer_s, s.shed, s.swing_from, s.shed_from, s.shed_goal, s.released_s, s.anim_speed}) {
    EXPECT_TRUE(std::isfinite(x)) << what;
  }
}

void expect_same(const FootLock& a, const FootLock& b) {
  EXPECT_EQ(a.state, b.state);
  EXPECT_EQ(a.target, b.target);
  EXPECT_EQ(a.offset, b.offset);
  EXPECT_EQ(a.offset_vel, b.offset_vel);
  EXPECT_EQ(a.from, b.from);
  EXPECT_EQ(a.timer_s, b.timer_s);
  EXPECT_EQ(a.last_goal, b.last_goal);
  EXPECT_EQ(a.goal_vel, b.goal_vel);
  EXPECT_EQ(a.carry, b.carry);
  EXPECT_EQ(a.carry_vel, b.carry_vel);
  EXPECT_EQ(a.shed, b.shed);
  EXPECT_EQ(a.swing_from, b.swing_from);
  EXPECT_EQ(a.shed_from, b.shed_from);
  EXPECT_EQ(a.shed_goal, b.shed_goal);
  EXPECT_EQ(a.released_s, b.released_s);
  EXPECT_EQ(a.anim_speed, b.anim_speed);
}

// A frame's input with the clip's toe at `anim` (moved from `prev`), drawn last at `drawn`.
FootLockInput input(const glm::vec3& anim, const glm::vec3& prev, const glm::vec3& drawn) {
  FootLockInput in;
  in.anim_toe = anim;
  in.anim_toe_prev = prev;
  in.drawn_toe_prev = drawn;
  in.floor_toe_m = kFloor;
  return in;
}

// A foot pinned at `pin` and drawn there (settled: no offset), its clip's toe at rest.
FootLock locked_at(const glm::vec3& pin) {
  FootLock s;
  s.state = FootLockState::kLocked;
  s.target = pin;
  s.last_goal = pin;
  s.anim_speed = 0.0f;
  return s;
}

double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

// A critically damped spring from x0 at rest toward 0, after t, halving every halflife h:
// x(t) = x0 (1 + y t) e^(-y t) with y = 2 ln2 / h (the header's h carries a 1e-5 guard).
double settled(double x0, double h, double t) {
  const double y = 2.0 * std::log(2.0) / (h + 1e-5);
  return x0 * (1.0 + y * t) * std::exp(-y * t);
}

TEST(FootLockTransition, FreshFootStartsUnlockedAtTheClipsToe) {
  const glm::vec3 a(1.5f, 0.07f, -3.0f);
  const FootLock fresh = fresh_foot_lock(a);
  EXPECT_EQ(fresh.state, FootLockState::kFree);
  EXPECT_EQ(fresh.last_goal, a);
  EXPECT_EQ(fresh.offset, glm::vec3(0.0f));
  EXPECT_LT(fresh.anim_speed, 0.0f);

  // Whatever the slot held before (here a foot mid-step far away), a fresh frame without a plant
  // is free at the clip's toe, with no speed.
  FootLock old = locked_at({9.0f, kFloor, 9.0f});
  old = start_foot_step(old, {9.0f, 0.1f, 9.0f});
  FootLockInput in = input(a, {-7.0f, 1.0f, 4.0f}, {3.0f, 3.0f, 3.0f});
  in.fresh = true;
  const FootLockStep next = step_foot_lock(old, in, FootLockParams{}, kDt);
  EXPECT_EQ(next.state.state, FootLockState::kFree);
  EXPECT_EQ(next.goal, a);
  EXPECT_EQ(next.state.offset, glm::vec3(0.0f));
  EXPECT_EQ(next.state.goal_vel, glm::vec3(0.0f));
  EXPECT_EQ(next.state.last_goal, a);
  EXPECT_LT(next.state.anim_speed, 0.0f) << "no speed on the first frame";
}

TEST(FootLockTransition, LockedFootStaysAtItsPinAndOnlyComesDown) {
  const glm::vec3 pin(1.0f, 0.05f, 2.0f);
  FootLock s = locked_at(pin);
  FootLockParams p;
  // The clip's toe slides away 1 cm per frame (at most 0.2 m: less than the step distance) while
  // the clips keep the weight on the foot and the other foot is pinned: the goal is the pin.
  glm::vec3 anim = pin;
  for (int f = 1; f <= 20; ++f) {
    const glm::vec3 prev = anim;
    anim = pin + glm::vec3(0.01f * f, 0.0f, 0.0f);
    FootLockInput in = input(anim, prev, s.last_goal);
    in.hold = true;
    in.other_locked = true;
    const FootLockStep next = step_foot_lock(s, in, p, kDt);
    ASSERT_EQ(next.state.state, FootLockState::kLocked) << f;
    EXPECT_EQ(next.goal, pin) << f;
    EXPECT_EQ(next.state.target, pin) << f;
    s = next.state;
  }
  // The clip's toe comes down to 3 cm (above the 2 cm floor): the pin follows it down to 3 cm;
  // the clip's toe rising again (heel-off) leaves it there; sunk below the floor, it stops at
  // the floor.
  const float clip_y[] = {0.03f, 0.06f, 0.0f};
  const float pinned_y[] = {0.03f, 0.03f, kFloor};
  for (int k = 0; k < 3; ++k) {
    const glm::vec3 prev = anim;
    anim.y = clip_y[k];
    FootLockInput in = input(anim, prev, s.last_goal);
    in.hold = true;
    const FootLockStep next = step_foot_lock(s, in, p, kDt);
    ASSERT_EQ(next.state.state, FootLockState::kLocked);
    EXPECT_EQ(next.goal, glm::vec3(pin.x, pinned_y[k], pin.z)) << k;
    s = next.state;
  }
}

// Pushing off: the other foot pinned (it carries the weight), the clip lifts this ball by 1 cm a
// frame. The pinned toe rises with it, frame by frame as the clip's does; x and z stay pinned.
// The same lift with the other foot in the air leaves the ball on its pin (alone on the ground,
// it bears the weight). And a ball the clip has lifted already when the other foot gets pinned
// catches up smoothly: never faster than the clip's own lift, never above it, within a
// millimetre 0.3 s on.
TEST(FootLockTransition, APinnedToeRisesWithTheClipsOnlyWhileTheOtherFootIsPinned) {
  const FootLockParams p;
  const glm::vec3 pin(0.2f, kFloor, 0.1f);
  for (const bool other_pinned : {true, false}) {
    FootLock s = locked_at(pin);
    glm::vec3 anim = pin;
    for (int f = 1; f <= 30; ++f) {
      const glm::vec3 prev = anim;
      if (f <= 6) anim.y += 0.01f;
      FootLockInput in = input(anim, prev, s.last_goal);
      in.hold = true;
      in.other_locked = other_pinned;
      const FootLockStep next = step_foot_lock(s, in, p, kDt);
      ASSERT_EQ(next.state.state, FootLockState::kLocked) << f;
      EXPECT_EQ(next.goal.x, pin.x) << f;
      EXPECT_EQ(next.goal.z, pin.z) << f;
      if (other_pinned) {
        EXPECT_NEAR(next.goal.y, anim.y, 1e-6f) << f;
      } else {
        EXPECT_EQ(next.goal.y, pin.y) << f;
      }
      s = next.state;
    }
  }
  // Lifted 6 cm by the clip while this foot bore the weight; then the other foot is pinned.
  FootLock s = locked_at(pin);
  glm::vec3 anim = pin + glm::vec3(0.0f, 0.06f, 0.0f);
  float last_y = pin.y;
  for (int f = 1; f <= 18; ++f) {
    FootLockInput in = input(anim, anim, s.last_goal);
    in.hold = true;
    in.other_locked = true;
    const FootLockStep next = step_foot_lock(s, in, p, kDt);
    EXPECT_GE(next.goal.y, last_y - 1e-6f) << f;
    EXPECT_LE(next.goal.y - last_y, 0.01f) << f;
    EXPECT_LE(next.goal.y, anim.y + 1e-6f) << f;
    last_y = next.goal.y;
    s = next.state;
  }
  EXPECT_NEAR(last_y, anim.y, 1e-3f);
}

// While the standing clips vote the feet (a creeping pedestrian), the clips' toe rising under a
// pinned foot is the walk's small share swinging it, not a push-off: with the other foot pinned,
// the pin stays where it is. One the gait clips had raised (6 cm, a push-off) when the standing
// clips took the vote comes down onto where they have the toe (4 mm above the floor) through the
// settling offset: no jump in the frame the vote changes, then the offset's critically damped
// decay, x0 (1 + y t) e^(-y t), to within a millimetre 0.3 s on.
TEST(FootLockTransition, WhileTheStandingClipsVoteAPinnedToeStandsWhereTheyHaveIt) {
  const FootLockParams p;
  const glm::vec3 pin(0.2f, kFloor, 0.1f);
  const float stand_y = kFloor + 0.004f;
  // A frame's input with the clips keeping the weight on the foot, the other foot pinned, and the
  // standing clips voting the feet.
  auto standing = [&](const glm::vec3& anim, const glm::vec3& prev, const glm::vec3& drawn) {
    FootLockInput in = input(anim, prev, drawn);
    in.hold = true;
    in.other_locked = true;
    in.standing_votes = true;
    in.stand_toe_y = stand_y;
    return in;
  };
  {
    FootLock s = locked_at(pin);
    glm::vec3 anim = pin;
    for (int f = 1; f <= 12; ++f) {
      const glm::vec3 prev = anim;
      anim.y += f <= 8 ? 0.01f : -0.01f;
      const FootLockStep next = step_foot_lock(s, standing(anim, prev, s.last_goal), p, kDt);
      ASSERT_EQ(next.state.state, FootLockState::kLocked) << f;
      EXPECT_EQ(next.goal, pin) << f;
      s = next.state;
    }
  }
  const float raised = kFloor + 0.06f;
  FootLock s = locked_at(glm::vec3(pin.x, raised, pin.z));
  const glm::vec3 anim(pin.x + 0.01f, kFloor + 0.08f, pin.z);  // the blend's toe, above both
  for (int f = 1; f <= 18; ++f) {
    const FootLockStep next = step_foot_lock(s, standing(anim, anim, s.last_goal), p, kDt);
    ASSERT_EQ(next.state.state, FootLockState::kLocked) << f;
    EXPECT_EQ(next.goal.x, pin.x) << f;
    EXPECT_EQ(next.goal.z, pin.z) << f;
    EXPECT_NEAR(next.state.target.y, stand_y, 1e-7f) << f;
    const double expected =
        stand_y + settled(raised - stand_y, p.release_halflife_s, (f - 1) * double{kDt});
    EXPECT_NEAR(next.goal.y, expected, 1e-5) << f;
    s = next.state;
  }
  EXPECT_NEAR(s.last_goal.y, stand_y, 1e-3f);
  // Below the floor the standing clips' toe is taken as the floor.
  FootLock low = locked_at(glm::vec3(pin.x, raised, pin.z));
  FootLockInput in = standing(anim, anim, low.last_goal);
  in.stand_toe_y = kFloor - 0.03f;
  EXPECT_NEAR(step_foot_lock(low, in, p, kDt).state.target.y, kFloor, 1e-7f);
}

TEST(FootLockTransition, PlantPinsWhereTheFootWasDrawn) {
  // plant_foot alone: drawn last at D (5 cm up), the clip's toe at 3 cm, the floor at 2 cm: the pin
  // is D's x, z at min(5, 3) = 3 cm, and the 2 cm it was drawn above that is the settling offset.
  const glm::vec3 d(0.4f, 0.05f, -0.2f);
  FootLockInput in = input({0.45f, 0.03f, -0.1f}, {0.44f, 0.03f, -0.1f}, d);
  in.plant = in.hold = true;
  const FootLock pinned = plant_foot(FootLock{}, in);
  EXPECT_EQ(pinned.state, FootLockState::kLocked);
  EXPECT_EQ(pinned.target, glm::vec3(0.4f, 0.03f, -0.2f));
  EXPECT_NEAR(pinned.offset.y, 0.02f, 1e-7f);
  EXPECT_EQ(pinned.offset.x, 0.0f);
  EXPECT_EQ(pinned.offset_vel, glm::vec3(0.0f));
  // Drawn below the floor: pinned on the floor, no offset (a foot never settles upward).
  in.drawn_toe_prev.y = 0.0f;
  EXPECT_EQ(plant_foot(FootLock{}, in).target.y, kFloor);
  EXPECT_EQ(plant_foot(FootLock{}, in).offset, glm::vec3(0.0f));
}

// A foot drawn with the clip's toe lands as the clip's toe drops 1.4 cm in one frame (the ball
// slapping down off the heel): pinned at the clip's toe, with no settling offset. Held at last
// frame's height, it would lift the ankle 1.4 cm against a nearly straight leg.
TEST(FootLockTransition, APlantFollowsTheClipsToeDownInTheFrameItLands) {
  const glm::vec3 prev(0.40f, 0.095f, -0.20f);
  FootLockInput in = input({0.41f, 0.081f, -0.19f}, prev, prev);
  in.plant = in.hold = true;
  const FootLock pinned = plant_foot(FootLock{}, in);
  EXPECT_EQ(pinned.state, FootLockState::kLocked);
  EXPECT_EQ(pinned.target, glm::vec3(0.40f, 0.081f, -0.20f));
  EXPECT_EQ(pinned.offset, glm::vec3(0.0f));
  // Drawn 2 cm above the clip last frame: those 2 cm (not the 3.4 to the clip's toe now) settle.
  in.drawn_toe_prev.y = prev.y + 0.02f;
  EXPECT_NEAR(plant_foot(FootLock{}, in).offset.y, 0.02f, 1e-6f);
}

TEST(FootLockTransition, ReleasingFootReplantsAtTheDrawnPositionAndSettles) {
  // Mid-release (the offset half shed), the clips plant the foot again and its ball is at rest:
  // it is pinned where it was drawn last frame, and the 1 cm it was drawn above the clip's toe
  // settles on the release spring: after one frame 0.01 (1 + y dt) e^(-y dt).
  FootLockParams p;
  FootLock s = release_foot_lock(FootLock{}, {0.0f, kFloor, 0.0f}, glm::vec3(0.0f),
                                 {0.3f, kFloor, 0.0f}, glm::vec3(0.0f));
  s.shed = 0.5f;
  s.anim_speed = 0.1f;
  const glm::vec3 drawn(0.15f, 0.04f, 0.05f);
  const glm::vec3 anim(0.3f, 0.03f, 0.0f);
  FootLockInput in = input(anim, anim, drawn);  // the clip's toe is still: at rest
  in.plant = in.hold = true;
  const FootLockStep next = step_foot_lock(s, in, p, kDt);
  ASSERT_EQ(next.state.state, FootLockState::kLocked);
  EXPECT_EQ(next.state.target, glm::vec3(0.15f, 0.03f, 0.05f));
  EXPECT_FLOAT_EQ(next.goal.x, 0.15f);
  EXPECT_FLOAT_EQ(next.goal.z, 0.05f);
  EXPECT_NEAR(next.goal.y, 0.03 + settled(0.01, p.release_halflife_s, kDt), 1e-6);
  EXPECT_GT(next.goal.y, 0.03f + 0.009f) << "settles over frames, not at once";

  // Not at rest (the ball still slows down: 3 m/s after 4 m/s) while the other foot is pinned,
  // nothing changes state.
  FootLock rolling = s;
  rolling.anim_speed = 4.0f;
  FootLockInput fast = input(anim, anim - glm::vec3(3.0f * kDt, 0.0f, 0.0f), drawn);
  fast.plant = fast.hold = true;
  fast.still_speed_m_s = 0.5f;
  fast.other_locked = true;
  EXPECT_EQ(step_foot_lock(rolling, fast, p, kDt).state.state, FootLockState::kReleasing);
  // The same with the other foot off the ground: this one carries the weight, and is pinned
  // where it was drawn at once.
  fast.other_locked = false;
  const FootLockStep weight = step_foot_lock(rolling, fast, p, kDt);
  ASSERT_EQ(weight.state.state, FootLockState::kLocked);
  EXPECT_EQ(weight.state.target, glm::vec3(0.15f, 0.03f, 0.05f));
  // Not planted by the clips, it is not pinned whatever the other foot does.
  fast.plant = fast.hold = false;
  EXPECT_EQ(step_foot_lock(rolling, fast, p, kDt).state.state, FootLockState::kReleasing);
}

TEST(FootLockTransition, ReleaseShedsTheOffsetOverTheSwingWithNoJump) {
  // Pinned at the origin while the clip's toe is 0.3 m ahead; the clips lift the foot and swing
  // it over N = 30 frames (0.5 s), progress k / N, the toe 2 cm further each frame, level on the
  // first frame (so no vertical offset arises). foot_lock.h's rule (smooth in the swing's progress,
  // in no less than twice the halflife): shed = min(smoothstep(k / N),
  // smoothstep(t / (2 halflife))), t = (k + 1) dt the time since the release (both rise, so the
  // running maximum is the current value); the goal is the clip's toe plus the offset taken
  // against the clip's toe of the frame before, (0 - 0.28) (1 - shed), plus the foot's rest
  // against the clip's 1.2 m/s carried on by a critically damped spring from 0 (v0 t e^{-y t}),
  // and the foot is free once shed reaches 1 (what is left of the carry goes on as its offset).
  FootLockParams p;
  constexpr int kN = 30;
  const glm::vec3 pin(0.0f, kFloor, 0.0f);
  FootLock s = locked_at(pin);
  auto anim_at = [](int k) {
    return glm::vec3(0.3f + 0.02f * k, kFloor + 0.04f * std::sin(3.14159265f * k / kN), 0.0f);
  };
  glm::vec3 prev_anim = anim_at(0) - glm::vec3(0.02f, 0.0f, 0.0f);
  for (int k = 0; k <= kN; ++k) {
    FootLockInput in = input(anim_at(k), prev_anim, s.last_goal);
    in.swing_progress = static_cast<float>(k) / kN;
    const FootLockStep next = step_foot_lock(s, in, p, kDt);
    const double t = (k + 1) * static_cast<double>(kDt);
    const double shed = std::min(smoothstep(static_cast<double>(k) / kN),
                                 smoothstep(t / (2.0 * p.release_halflife_s)));
    const double v0 = -0.02 / kDt;
    const double y = 0.5 * halflife_to_damping(p.carry_halflife_s);
    const double carry = v0 * t * std::exp(-y * t);
    if (k == 0) {
      EXPECT_EQ(next.state.state, FootLockState::kReleasing);
      EXPECT_NEAR(next.state.offset.x, -0.28f, 1e-6f);
      // It sets off from rest: on the first frame it moves a third of the clip's 2 cm.
      EXPECT_LT(next.goal.x - pin.x, 0.5 * 0.02) << "no jump to the clip's speed";
    }
    EXPECT_NEAR(next.goal.x, anim_at(k).x - 0.28 * (1.0 - shed) + carry, 1e-5) << k;
    EXPECT_NEAR(next.goal.y, anim_at(k).y, 1e-6f) << k;
    EXPECT_EQ(next.state.state, k < kN ? FootLockState::kReleasing : FootLockState::kFree) << k;
    prev_anim = anim_at(k);
    s = next.state;
  }
  // Free: the clip's toe, plus what is left of the carried rest (its offset now, a couple of
  // millimetres after half a second, decaying on).
  const double t_end = (kN + 1) * static_cast<double>(kDt);
  const double left = 1.2 * t_end *
                      std::exp(-0.5 * halflife_to_damping(p.carry_halflife_s) * t_end);
  EXPECT_NEAR(glm::length(s.offset), left, 1e-4);
  FootLockInput in = input(anim_at(kN + 1), anim_at(kN), s.last_goal);
  EXPECT_LT(glm::length(step_foot_lock(s, in, p, kDt).goal - anim_at(kN + 1)), left)
      << "free: the clip's toe, the carried rest still decaying";
}

// The blend changes clips mid-swing and the swing's progress leaps from 0.13 to 0.55 in a frame
// (a quarter of a swing is more than any swing advances in one): the offset is not shed in a
// jump but from there over the rest of the swing; the foot moves on no faster than it did.
TEST(FootLockTransition, ALeapInTheSwingsProgressShedsNoOffsetAtOnce) {
  FootLockParams p;
  FootLock s = release_foot_lock(FootLock{}, {0.0f, kFloor, 0.0f}, glm::vec3(0.0f),
                                 {0.2f, kFloor, 0.0f}, glm::vec3(0.0f));
  const glm::vec3 anim(0.2f, kFloor + 0.05f, 0.0f);
  float progress = 0.0f, last_step = 0.0f;
  glm::vec3 last_goal(0.0f, kFloor, 0.0f);
  for (int f = 1; f <= 14; ++f) {
    progress = f == 10 ? 0.55f : progress + 0.013f;
    FootLockInput in = input(anim, anim, last_goal);
    in.swing_progress = progress;
    const FootLockStep next = step_foot_lock(s, in, p, kDt);
    ASSERT_EQ(next.state.state, FootLockState::kReleasing) << f;
    const float step = std::abs(next.goal.x - last_goal.x);
    if (f == 10) {
      EXPECT_LE(step, 1.5f * last_step + 1e-4f) << "a leap of the progress";
    }
    last_step = step;
    last_goal = next.goal;
    s = next.state;
  }
}

TEST(FootLockTransition, LateReleaseStillTakesTwiceTheHalflife) {
  // Released at 90 % of the swing, landing (progress 1) on the next frame: the swing asks for all
  // of it at once, so the time bound rules: shed = smoothstep((k + 1) dt / 0.12 s), free once
  // (k + 1) dt >= 0.12 s, i.e. on frame k = 7 (8 / 60 = 0.133 s; 7 / 60 = 0.117 s is short).
  FootLockParams p;
  const glm::vec3 pin(0.0f, kFloor, 0.0f);
  FootLock s = locked_at(pin);
  const glm::vec3 anim(0.1f, kFloor, 0.0f);
  for (int k = 0; k <= 7; ++k) {
    FootLockInput in = input(anim, anim, s.last_goal);
    in.swing_progress = k == 0 ? 0.9f : 1.0f;
    const FootLockStep next = step_foot_lock(s, in, p, kDt);
    const double shed = smoothstep((k + 1) * static_cast<double>(kDt) / (2.0 * 0.06));
    EXPECT_NEAR(next.goal.x, 0.1 - 0.1 * (1.0 - (k == 0 ? 0.0 : shed)), 1e-5) << k;
    EXPECT_EQ(next.state.state, k < 7 ? FootLockState::kReleasing : FootLockState::kFree) << k;
    s = next.state;
  }
}

TEST(FootLockTransition, TheClipsLiftingAStepReleasesItFromWhereItIsAtItsSpeed) {
  // Stepping, last drawn at F moving at V; the clips lift the foot (no hold): released from F
  // toward the clip's toe A, the offset F - A, its rate V - (the clip's toe speed).
  FootLock s = start_foot_step(locked_at({0.0f, kFloor, 0.0f}), {0.0f, kFloor, 0.0f});
  s.last_goal = {0.1f, 0.05f, 0.0f};
  s.goal_vel = {1.0f, 0.2f, 0.0f};
  const glm::vec3 a(0.3f, 0.04f, 0.0f), a_prev(0.28f, 0.04f, 0.0f);
  FootLockInput in = input(a, a_prev, s.last_goal);
  const FootLockStep next = step_foot_lock(s, in, FootLockParams{}, kDt);
  ASSERT_EQ(next.state.state, FootLockState::kReleasing);
  EXPECT_EQ(next.state.from, glm::vec3(0.1f, 0.05f, 0.0f));
  // Horizontally nothing is shed on the release's first frame (progress 0). The offset is taken
  // from where the clip's toe was when the step was last drawn (A_prev), so this frame the goal
  // is F plus the clip's toe's move (A - A_prev), plus the step's own velocity relative to the
  // clip's toe, V - A', carried on (inertialization, not a jump to the clip's speed) by a
  // critically damped spring from 0: one frame of it is v0 dt e^{-y dt}.
  const FootLockParams p;
  const double v0 = 1.0 - 0.02 / kDt;
  const double y = 0.5 * halflife_to_damping(p.carry_halflife_s);
  EXPECT_NEAR(next.state.offset.x, 0.1 - 0.28, 1e-6);
  EXPECT_NEAR(next.state.offset_vel.x, v0, 1e-3f);
  EXPECT_NEAR(next.state.carry_vel.x, v0 * std::exp(-y * kDt) * (1.0 - y * kDt), 1e-3f);
  EXPECT_NEAR(next.goal.x, 0.1 + 0.02 + v0 * kDt * std::exp(-y * kDt), 1e-5);
  EXPECT_NEAR(next.goal.z, 0.0f, 1e-6f);
  // So the drawn foot goes on at about the step's own speed V (the spring's first frame takes a
  // little of the difference off), neither stopping nor jumping to the clip's 1.2 m/s.
  const double moved = (next.goal.x - 0.1) / kDt;
  EXPECT_NEAR(moved, 1.0, 0.1);
  // The carried velocity dies out: a second later it is gone.
  FootLock r = next.state;
  for (int f = 0; f < 60; ++f) {
    in = input(a, a, r.last_goal);
    r = step_foot_lock(r, in, p, kDt).state;
  }
  EXPECT_LT(glm::length(r.carry), 1e-4f);
  EXPECT_LT(glm::length(r.carry_vel), 1e-3f);
  // A pinned foot's release carries its rest: the clip's toe moving at 1 m/s (and up), the drawn
  // foot standing still, the horizontal difference -1 m/s is carried on from 0 (no height: the
  // foot follows the clip's lift on its own spring).
  const FootLock released = release_foot_lock(locked_at({0.0f, kFloor, 0.0f}),
                                              {0.0f, kFloor, 0.0f}, glm::vec3(0.0f), a,
                                              glm::vec3(1.0f, 0.5f, 0.0f));
  EXPECT_EQ(released.carry, glm::vec3(0.0f));
  EXPECT_EQ(released.carry_vel, glm::vec3(-1.0f, 0.0f, 0.0f));
}

TEST(FootLockTransition, PinnedFootLeftBehindStepsFromItsPinOntoTheFloorWhereTheClipHasIt) {
  // Pinned at the origin, the clip's toe 0.3 m away (beyond the 0.25 m step distance) while the
  // other foot is pinned: the foot steps from its pin. The first frame (u = dt / T, under the
  // first fifth) only lifts it: y = h sin^2(pi u) above the floor, x and z stay.
  FootLockParams p;
  const glm::vec3 pin(0.0f, kFloor, 0.0f), to(0.3f, kFloor, 0.0f);
  FootLock s = locked_at(pin);
  FootLockInput in = input(to, to, pin);
  in.hold = true;
  in.other_locked = true;
  FootLockStep next = step_foot_lock(s, in, p, kDt);
  ASSERT_EQ(next.state.state, FootLockState::kStepping);
  EXPECT_EQ(next.state.from, pin);
  const double u = kDt / static_cast<double>(p.step_time_s);
  const double lift = p.step_height_m * std::pow(std::sin(3.14159265358979 * u), 2.0);
  EXPECT_EQ(next.goal.x, 0.0f);
  EXPECT_EQ(next.goal.z, 0.0f);
  EXPECT_NEAR(next.goal.y, kFloor + lift, 1e-6);
  // Without the other foot pinned it stays (one foot steps at a time).
  in.other_locked = false;
  EXPECT_EQ(step_foot_lock(s, in, p, kDt).state.state, FootLockState::kLocked);
  // Nor while the clips walk: their own swing of this foot comes and takes the offset, so it
  // stays pinned where it is (however far the clip's toe has drifted) and no step lifts it.
  in.other_locked = true;
  in.walking = true;
  for (const float away : {0.3f, 0.6f}) {
    FootLockInput far = in;
    far.anim_toe = far.anim_toe_prev = glm::vec3(away, kFloor, 0.0f);
    const FootLockStep held = step_foot_lock(s, far, p, kDt);
    EXPECT_EQ(held.state.state, FootLockState::kLocked) << away;
    EXPECT_EQ(held.goal, pin) << away;
  }
  in.walking = false;
  // Once step_time_s has passed it is pinned again, on the floor where the clip has the foot.
  s = next.state;
  for (int f = 0; f < 40 && s.state == FootLockState::kStepping; ++f) {
    in.other_locked = true;
    next = step_foot_lock(s, in, p, kDt);
    s = next.state;
  }
  ASSERT_EQ(s.state, FootLockState::kLocked);
  EXPECT_EQ(s.target, to);
  EXPECT_NEAR(s.timer_s, p.step_time_s, kDt + 1e-6f);
  // The blend's toe 15 cm up (the walk's share swinging it), the standing clips voting the feet:
  // the step is set down on the floor where the standing clips have the toe, not up there.
  FootLock creeper = locked_at(pin);
  FootLockInput lifted =
      input(to + glm::vec3(0.0f, 0.15f, 0.0f), to + glm::vec3(0.0f, 0.15f, 0.0f), pin);
  lifted.hold = lifted.other_locked = lifted.standing_votes = true;
  lifted.stand_toe_y = kFloor + 0.003f;
  for (int f = 0; f < 40 && (f == 0 || creeper.state == FootLockState::kStepping); ++f) {
    creeper = step_foot_lock(creeper, lifted, p, kDt).state;
  }
  ASSERT_EQ(creeper.state, FootLockState::kLocked);
  EXPECT_EQ(creeper.target, glm::vec3(to.x, kFloor + 0.003f, to.z));
  // Nor, the gait clips voting, at their toe's height: a step (as pose synthesis starts one for a
  // leg that cannot reach its pin) is set down on the floor.
  FootLock reached = start_foot_step(locked_at(pin), pin);
  lifted.standing_votes = false;
  for (int f = 0; f < 40 && reached.state == FootLockState::kStepping; ++f) {
    reached = step_foot_lock(reached, lifted, p, kDt).state;
  }
  ASSERT_EQ(reached.state, FootLockState::kLocked);
  EXPECT_EQ(reached.target, to);
}

TEST(FootLockTransition, NaNInputGivesADefinedStateAndNoNaN) {
  FootLockParams p;
  const glm::vec3 pin(0.0f, kFloor, 0.0f), a(0.1f, 0.03f, 0.05f);
  FootLock states[4];
  states[0] = fresh_foot_lock(a);
  states[1] = locked_at(pin);
  states[2] = release_foot_lock(states[1], pin, glm::vec3(0.0f), a, glm::vec3(0.0f));
  states[3] = start_foot_step(states[1], pin);
  for (const FootLock& s : states) {
    for (int field = 0; field < 9; ++field) {
      for (bool plant : {false, true}) {
        FootLockInput in = input(a, a - glm::vec3(0.01f, 0.0f, 0.0f), pin);
        in.plant = in.hold = plant;
        in.swing_progress = 0.5f;
        float dt = kDt;
        switch (field) {
          case 0:
            in.anim_toe.x = kNaN;
            break;
          case 1:
            in.anim_toe_prev.y = kNaN;
            break;
          case 2:
            in.drawn_toe_prev.z = std::numeric_limits<float>::infinity();
            break;
          case 3:
            in.floor_toe_m = kNaN;
            break;
          case 4:
            in.swing_progress = kNaN;
            break;
          case 5:
            in.still_speed_m_s = kNaN;
            break;
          case 6:
            dt = kNaN;
            break;
          case 7:
            in.standing_votes = true;
            in.stand_toe_y = kNaN;
            break;
          case 8:  // no floor and no standing clips' toe either
            in.standing_votes = true;
            in.stand_toe_y = kNaN;
            in.floor_toe_m = kNaN;
            break;
        }
        const FootLockStep next = step_foot_lock(s, in, p, dt);
        expect_defined(next.state, "after an unusable input");
        EXPECT_TRUE(finite(next.goal)) << field;
        if (field == 0 || field == 6) {
          // Nothing to follow or no time: the foot stays as it was, drawn where it was.
          expect_same(next.state, s);
          EXPECT_EQ(next.goal, s.last_goal);
        }
        // Frames more of the same input stay near the clip's toe (an unusable value never reaches
        // the state: no offset of -lowest() that turns to inf, then NaN).
        if (field != 0 && field != 6) {
          FootLock again = next.state;
          for (int f = 0; f < 3; ++f) {
            in.drawn_toe_prev = again.last_goal;
            const FootLockStep more = step_foot_lock(again, in, p, kDt);
            ASSERT_TRUE(finite(more.goal)) << field << " frame " << f;
            EXPECT_LT(glm::length(more.goal - a), 1.0f) << field << " frame " << f;
            again = more.state;
          }
        }
        // The next good frame goes on from there, finite.
        const FootLockStep after = step_foot_lock(next.state, input(a, a, next.goal), p, kDt);
        expect_defined(after.state, "a good frame after");
        EXPECT_TRUE(finite(after.goal));
      }
    }
  }
  // An unusable previous drawn toe counts as the clip's toe: a plant pins there.
  FootLockInput in = input(a, a, glm::vec3(kNaN));
  in.plant = in.hold = true;
  const FootLockStep pinned = step_foot_lock(states[0], in, p, kDt);
  EXPECT_EQ(pinned.state.state, FootLockState::kLocked);
  EXPECT_EQ(pinned.state.target, a);
  // The transitions the caller starts take no NaN in either.
  expect_defined(start_foot_step(states[1], glm::vec3(kNaN)), "step from NaN");
  expect_defined(release_foot_lock(states[1], glm::vec3(kNaN), glm::vec3(kNaN), glm::vec3(kNaN),
                                   glm::vec3(kNaN)),
                 "release with NaN");
  // A fresh frame without a usable clip toe is a default foot at the origin.
  FootLockInput bad = input(glm::vec3(kNaN), a, a);
  bad.fresh = true;
  const FootLockStep fresh = step_foot_lock(states[2], bad, p, kDt);
  EXPECT_EQ(fresh.state.state, FootLockState::kFree);
  EXPECT_EQ(fresh.goal, glm::vec3(0.0f));
}

}  // namespace
}  // namespace gk
