// The foot-lock state machine alone (mediator/foot_lock), fed hand-built clip toes at 60 Hz:
// pinning, the heel-off rule, release without a snap (and no faster than the clips swing),
// re-planting steps (set down where they were carried), resets, and no NaN.

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "mediator/foot_lock.h"
#include "mediator/springs.h"

namespace gk {
namespace {

constexpr float kDt = 1.0f / 60.0f;
constexpr float kFloor = 0.02f;

float horizontal(const glm::vec3& a, const glm::vec3& b) {
  return std::hypot(a.x - b.x, a.z - b.z);
}

// Drives one foot as pose synthesis does: last frame's goal is the drawn toe.
struct Foot {
  FootLock lock;
  FootLockParams params;
  glm::vec3 goal{0.0f}, anim{0.0f};
  bool started = false;
  bool walking = false;  // the gait clips step the feet (a walk or a run)
  bool flight = false;   // the clips run (no double support)
  glm::vec3 step(const glm::vec3& anim_toe, bool plant, bool hold, float progress = 0.0f,
                 bool other_locked = false, float still_speed = 0.0f, float clip_speed = -1.0f) {
    FootLockInput in;
    in.anim_toe = anim_toe;
    in.anim_toe_prev = started ? anim : anim_toe;
    in.drawn_toe_prev = started ? goal : anim_toe;
    in.fresh = !started;
    in.plant = plant;
    in.hold = hold;
    in.swing_progress = progress;
    in.other_locked = other_locked;
    in.walking = walking || flight;
    in.flight = flight;
    in.floor_toe_m = kFloor;
    in.still_speed_m_s = still_speed;
    in.clip_speed_m_s = clip_speed;
    started = true;
    anim = anim_toe;
    const FootLockStep next = step_foot_lock(lock, in, params, kDt);
    lock = next.state;
    goal = next.goal;
    return goal;
  }
};

TEST(FootLock, PlantedFootIsPinnedWhereItWasDrawnAndOnlyComesDown) {
  Foot foot;
  foot.step({0.0f, 0.06f, 0.0f}, false, false);
  EXPECT_EQ(foot.lock.state, FootLockState::kFree);
  const glm::vec3 drawn = foot.step({0.01f, 0.045f, 0.002f}, false, false);
  // Plants: pinned at last frame's drawn toe (x, z), not at the clip's toe of this frame.
  glm::vec3 prev = foot.step({0.02f, 0.035f, 0.004f}, true, true);
  EXPECT_EQ(foot.lock.state, FootLockState::kLocked);
  EXPECT_FLOAT_EQ(prev.x, drawn.x);
  EXPECT_FLOAT_EQ(prev.z, drawn.z);
  // The clip's toe slides on (1 cm per frame), comes down 5 mm per frame below the floor, then
  // rises again (heel-off) while the clips keep the weight on it.
  for (int f = 3; f <= 40; ++f) {
    const float y = f < 10 ? 0.035f - 0.005f * (f - 2) : 0.005f + 0.002f * (f - 10);
    const glm::vec3 g = foot.step({0.02f + 0.01f * (f - 2), y, 0.004f + 0.002f * f}, false, true);
    ASSERT_EQ(foot.lock.state, FootLockState::kLocked) << f;
    EXPECT_FLOAT_EQ(g.x, drawn.x) << f;
    EXPECT_FLOAT_EQ(g.z, drawn.z) << f;
    EXPECT_LE(g.y, prev.y + 1e-7f) << "a pinned toe went up on frame " << f;
    EXPECT_GE(g.y, kFloor - 1e-6f) << f;
    prev = g;
  }
  // Settled on the floor: the 1 cm landing offset decays with a 0.06 s halflife, and 38 frames
  // (0.63 s, over 10 halflives) leave far less than 0.1 mm.
  EXPECT_NEAR(prev.y, kFloor, 1e-4f);
}

// A runner pushes off on its toes into the air: the clips raise the ball while the other foot is
// off the ground. Walking, alone on the ground, the ball bears the weight and stays down; running,
// it rises with the clips' (held down, it was snatched up by the whole rise in the frames after
// the release). Either way, released, it never jumps.
TEST(FootLock, InARunThePinnedBallRisesWithThePushOff) {
  for (const bool run : {false, true}) {
    Foot foot;
    foot.walking = true;  // a walk's foot alone on the ground, or a run's
    foot.flight = run;
    foot.step({0.0f, kFloor, 0.0f}, true, true);
    ASSERT_EQ(foot.lock.state, FootLockState::kLocked);
    // Push-off: the clip's ball rises 5 mm a frame for 8 frames, the weight still on it.
    float highest = kFloor;
    for (int f = 1; f <= 8; ++f) {
      const glm::vec3 g = foot.step({0.0f, kFloor + 0.005f * f, 0.0f}, false, true);
      ASSERT_EQ(foot.lock.state, FootLockState::kLocked) << f;
      highest = g.y;
    }
    if (run) {
      EXPECT_NEAR(highest, kFloor + 0.04f, 1e-5f);  // risen with the clip's ball
    } else {
      EXPECT_NEAR(highest, kFloor, 1e-6f);  // stays down: the heel rises about it
    }
    // Released as the clip's ball goes on rising at 5 mm a frame (0.3 m/s): the run's drawn ball
    // goes on with it, a frame's rise a frame (the release's first frame used to lift it by two:
    // the pin raised to this frame's height, then the clip's rise once more, a 4 cm jump at a
    // captured run's push-off), the walk's catches up the whole push-off over the release, never
    // at once.
    float prev = highest, most = 0.0f;
    for (int f = 9; f <= 12; ++f) {
      const glm::vec3 g = foot.step({0.0f, kFloor + 0.005f * f, 0.0f}, false, false, 0.1f);
      most = std::max(most, g.y - prev);
      prev = g.y;
    }
    EXPECT_LT(most, run ? 0.0051f : 0.03f) << run;
  }
}

// The clips may plant a foot whose ball still rolls forward off the heel: the lock waits until the
// ball is at rest (slower than the still speed) or has stopped slowing down, and pins it where it
// was drawn then, so the drawn foot never stops dead from swing speed.
TEST(FootLock, PlantWaitsForTheBallToComeToRest) {
  const float still = 0.5f;  // [m/s]
  Foot foot;
  float x = 0.0f;
  foot.step({x, 0.03f, 0.0f}, false, false, 0.9f, false, still);
  // Decelerating 4, 3, 2, 1.2, 0.8, 0.4 m/s with the plant on from the first of these frames,
  // the other foot pinned (it bears the weight meanwhile).
  const float speeds[] = {4.0f, 3.0f, 2.0f, 1.2f, 0.8f, 0.4f};
  float drawn_before = 0.0f;
  for (float v : speeds) {
    drawn_before = foot.goal.x;
    x += v * kDt;
    foot.step({x, kFloor, 0.0f}, true, true, 0.0f, true, still);
    if (v > still) {
      EXPECT_NE(foot.lock.state, FootLockState::kLocked) << v;
      EXPECT_FLOAT_EQ(foot.goal.x, x) << "a foot not yet pinned is where the clip has it";
    }
  }
  ASSERT_EQ(foot.lock.state, FootLockState::kLocked);
  EXPECT_FLOAT_EQ(foot.goal.x, drawn_before);
  // Pinned: the clip's toe creeps on, the drawn one stays.
  for (int f = 0; f < 10; ++f)
    foot.step({x += 0.001f, kFloor, 0.0f}, true, true, 0.0f, true, still);
  EXPECT_FLOAT_EQ(foot.goal.x, drawn_before);

  // A ball that never gets slower than the still speed (the crowd walks faster than the clip) is
  // pinned at its slowest: on the first frame it is no slower than the one before.
  Foot fast;
  x = 0.0f;
  fast.step({x, 0.03f, 0.0f}, false, false, 0.9f, false, still);
  const float slowing[] = {3.0f, 2.0f, 1.5f, 1.5f};
  int locked_at = -1;
  for (int i = 0; i < 4; ++i) {
    x += slowing[i] * kDt;
    fast.step({x, kFloor, 0.0f}, true, true, 0.0f, true, still);
    if (locked_at < 0 && fast.lock.state == FootLockState::kLocked) locked_at = i;
  }
  EXPECT_EQ(locked_at, 3);
}

// A foot that must take the weight while it still moves fast (the other foot has left the ground:
// a run's landing, or a blend between a run and a walk) is pinned at once, but its speed falls
// off from what it was over a few frames, as a critically damped spring of glide_halflife_s
// stops it, not to zero in one frame (which snaps the ankle and knee).
TEST(FootLock, AFootThatMustTakeTheWeightWhileMovingGlidesToItsPin) {
  Foot foot;
  const float still = 0.5f;  // [m/s]
  float x = 0.0f;
  foot.step({x, 0.03f, 0.0f}, false, false, 0.9f, false, still);
  // Swinging in at 4 m/s, still slowing (so not at rest), the other foot off the ground.
  float v = 4.0f;
  for (int f = 0; f < 4; ++f) {
    x += v * kDt;
    foot.step({x, kFloor, 0.0f}, false, false, 0.95f, false, still);
  }
  const float drawn_speed = v;
  const float pinned_from = foot.goal.x;
  float prev_x = foot.goal.x, prev_speed = drawn_speed, max_drop = 0.0f;
  for (int f = 0; f < 30; ++f) {
    v = std::max(0.0f, v - 0.3f);
    x += v * kDt;
    foot.step({x, kFloor, 0.0f}, true, true, 0.0f, false, still);
    ASSERT_EQ(foot.lock.state, FootLockState::kLocked) << f;
    const float speed = (foot.goal.x - prev_x) / kDt;
    EXPECT_GE(speed, -1e-3f) << "the glide overshot its pin and came back, frame " << f;
    EXPECT_LE(speed, prev_speed + 1e-3f) << "the glide sped up, frame " << f;
    max_drop = std::max(max_drop, prev_speed - speed);
    prev_x = foot.goal.x;
    prev_speed = speed;
  }
  // Exponential at the glide's damping y = 2 ln 2 / halflife: the first frame keeps
  // exp(-y dt) of the speed (46%), so no frame loses more than 54% of 4 m/s (all of it before).
  const float y = 2.0f * std::numbers::ln2_v<float> / foot.params.glide_halflife_s;
  EXPECT_LE(max_drop, drawn_speed * (1.0f - std::exp(-y * kDt)) + 0.01f);
  EXPECT_LT(prev_speed, 0.01f);  // at rest after half a second
  // It comes to rest v / y beyond where it was drawn when pinned (8.7 cm): a short glide.
  EXPECT_NEAR(foot.goal.x - pinned_from, drawn_speed / y, 0.005f);

  // The clip's ball has landed (at rest) but the drawn foot is still carried at 3 m/s, faster
  // than it by more than the body's speed (twice the still speed): it glides as well.
  Foot carried;
  x = 0.0f;
  carried.step({x, 0.03f, 0.0f}, false, false, 0.9f, true, still);
  for (int f = 0; f < 4; ++f)
    carried.step({x += 3.0f * kDt, kFloor, 0.0f}, false, false, 0.95f, true, still);
  const float carried_from = carried.goal.x;
  carried.step({x, kFloor, 0.0f}, true, true, 0.0f, true, still);
  ASSERT_EQ(carried.lock.state, FootLockState::kLocked);
  // Its first frame covers the glide's share 1 - exp(-y dt) of 3 / y: 2.1 m/s, not 0.
  EXPECT_NEAR(carried.goal.x - carried_from, 3.0f / y * (1.0f - std::exp(-y * kDt)), 1e-3f);
  for (int f = 0; f < 30; ++f) carried.step({x, kFloor, 0.0f}, true, true, 0.0f, true, still);
  EXPECT_NEAR(carried.goal.x - carried_from, 3.0f / y, 0.005f);

  // A velocity no foot has (the clip's toe moved 30 m in a frame: a reset, a teleport) glides no
  // further than the clips' own swing speed would carry it.
  Foot jumped;
  jumped.params.swing_speed_m_s = 3.0f;
  jumped.step({0.0f, 0.03f, 0.0f}, false, false, 0.9f, false, still);
  jumped.step({30.0f, kFloor, 0.0f}, false, false, 0.95f, false, still);
  const float jumped_from = jumped.goal.x;
  jumped.step({30.0f, kFloor, 0.0f}, true, true, 0.0f, false, still);
  ASSERT_EQ(jumped.lock.state, FootLockState::kLocked);
  for (int f = 0; f < 30; ++f) jumped.step({30.0f, kFloor, 0.0f}, true, true, 0.0f, false, still);
  EXPECT_LE(jumped.goal.x - jumped_from, 3.0f / y + 1e-4f);
}

// A ball at rest in the clips has landed, though the blend's changing weights (a walk fading in
// over a standing pose as an agent speeds up) still carry the drawn foot slowly on, slowing all
// the while: it is pinned at once rather than glided along the floor until the weights settle;
// but not a ball the clips still move (faster than the still speed), nor a foot still moving
// faster over the ground than the body travels (twice the still speed), whose stop would be a
// jolt; and not without the clips' own ball speed.
TEST(FootLock, BallAtRestInTheClipsIsPinnedThoughTheBlendStillMovesIt) {
  const float still = 0.2f;  // [m/s] half the body's travel speed
  for (float clip_speed : {0.05f, 0.3f, -1.0f}) {
    Foot foot;
    foot.step({0.0f, 0.04f, 0.0f}, false, false, 0.9f, true, still);
    float x = 0.0f;
    int locked_at = -1;
    // Slowing 0.36, 0.35, ... m/s: above the still speed, never "no slower than before".
    for (int i = 0; i < 8; ++i) {
      x += (0.36f - 0.01f * i) * kDt;
      foot.step({x, kFloor, 0.0f}, true, true, 0.0f, true, still, clip_speed);
      if (locked_at < 0 && foot.lock.state == FootLockState::kLocked) locked_at = i;
    }
    if (clip_speed >= 0.0f && clip_speed <= still) {
      EXPECT_EQ(locked_at, 0);
    } else {
      EXPECT_EQ(locked_at, -1) << "clip speed " << clip_speed
                               << ": the glide is (or may be) the ball's own";
    }
  }
  // Faster than the body travels (a swing's last frames as the blend changes clips): not pinned.
  Foot fast;
  fast.step({0.0f, 0.04f, 0.0f}, false, false, 0.9f, true, still);
  float x = 0.0f;
  for (int i = 0; i < 4; ++i) {
    x += (1.5f - 0.2f * i) * kDt;
    fast.step({x, kFloor, 0.0f}, true, true, 0.0f, true, still, 0.0f);
    EXPECT_NE(fast.lock.state, FootLockState::kLocked) << i;
  }
}

// A foot planted on the floor at the origin on its first frame: its lock, pinned there, and the
// input that pinned it (no longer fresh), for a test to change.
struct PinnedAtOrigin {
  FootLockParams params;
  FootLock lock;
  FootLockInput in;
  PinnedAtOrigin() {
    in.anim_toe = in.anim_toe_prev = in.drawn_toe_prev = glm::vec3(0.0f, kFloor, 0.0f);
    in.fresh = true;
    in.plant = in.hold = true;
    in.floor_toe_m = kFloor;
    lock = step_foot_lock(lock, in, params, kDt).state;
    in.fresh = false;
  }
};

// Walking, a trailing foot whose clip lifts it while the leading foot is still coming down keeps
// its lock until the leading one is pinned; then it is let go.
TEST(FootLock, TrailingFootWaitsForTheLeadingOneToLand) {
  PinnedAtOrigin pinned;
  auto& [params, lock, in] = pinned;
  ASSERT_EQ(lock.state, FootLockState::kLocked);
  in.plant = in.hold = false;  // the clip lifts the foot
  in.other_landing = true;     // while the other is not pinned yet
  for (int f = 0; f < 3; ++f) {
    in.anim_toe_prev = in.anim_toe;
    in.anim_toe += glm::vec3(0.01f, 0.005f, 0.0f);
    const FootLockStep next = step_foot_lock(lock, in, params, kDt);
    lock = next.state;
    const glm::vec3 goal = next.goal;
    EXPECT_EQ(lock.state, FootLockState::kLocked);
    EXPECT_FLOAT_EQ(goal.x, 0.0f);
    EXPECT_FLOAT_EQ(goal.y, kFloor);
  }
  in.other_landing = false;  // the other foot is pinned: this one goes
  in.anim_toe_prev = in.anim_toe;
  in.anim_toe += glm::vec3(0.01f, 0.005f, 0.0f);
  lock = step_foot_lock(lock, in, params, kDt).state;
  EXPECT_EQ(lock.state, FootLockState::kReleasing);
}

// A pinned foot the standing clips have left behind re-plants with a step, but not while the
// other foot has only just landed on its heel: the body would stand on one heel, both toes in the
// air. It steps on the first frame the other is flat.
TEST(FootLock, NoReplantingStepWhileTheOtherFootIsOnItsHeel) {
  PinnedAtOrigin pinned;
  auto& [params, lock, in] = pinned;
  ASSERT_EQ(lock.state, FootLockState::kLocked);
  in.other_locked = true;
  in.other_on_heel = true;
  // The standing clips turn away: their toe ends up well beyond the step distance from the pin.
  const glm::vec3 away(params.step_distance_m * 1.5f, kFloor, 0.0f);
  for (int f = 1; f <= 10; ++f) {
    in.anim_toe_prev = in.anim_toe;
    in.anim_toe = away * (static_cast<float>(f) / 10.0f);
    in.anim_toe.y = kFloor;
    const FootLockStep next = step_foot_lock(lock, in, params, kDt);
    lock = next.state;
    EXPECT_EQ(lock.state, FootLockState::kLocked) << f;
    EXPECT_NEAR(horizontal(next.goal, glm::vec3(0.0f)), 0.0f, 1e-6f) << f;
    in.drawn_toe_prev = next.goal;
  }
  in.other_on_heel = false;  // the other foot is flat now
  in.anim_toe_prev = in.anim_toe;
  lock = step_foot_lock(lock, in, params, kDt).state;
  EXPECT_EQ(lock.state, FootLockState::kStepping);
}

TEST(FootLock, PlantedBelowTheClipsToeTheFootDoesNotRise) {
  // Drawn on the floor, 3 cm below the clip's toe, when it plants (the clip's toe stays 3 cm
  // above the floor): the pinned toe may not go up towards the clip's.
  Foot foot;
  foot.step({0.0f, 0.05f, 0.0f}, false, false);
  foot.goal.y = kFloor;  // as if drawn lower last frame (e.g. a release offset)
  glm::vec3 prev = foot.goal;
  for (int f = 0; f < 20; ++f) {
    const glm::vec3 g = foot.step({0.0f, 0.05f, 0.01f * f}, f == 0, true);
    ASSERT_EQ(foot.lock.state, FootLockState::kLocked);
    EXPECT_LE(g.y, prev.y + 1e-7f) << "a pinned toe went up on frame " << f;
    prev = g;
  }
}

// A foot pinned at the origin on the floor for 20 frames while the clip's toe slides 1 cm per
// frame ahead and, over frames 16-20, rises 2 mm per frame (heel-off): the release starts at 21.
Foot pinned_then_held() {
  Foot foot;
  foot.step({0.0f, kFloor, 0.0f}, true, true);
  for (int f = 1; f <= 20; ++f) {
    foot.step({0.01f * f, kFloor + (f > 15 ? 0.002f * (f - 15) : 0.0f), 0.0f}, false, true);
  }
  return foot;
}

TEST(FootLock, ReleaseMovesContinuouslyAndReachesTheClipsToeAtLanding) {
  Foot foot = pinned_then_held();
  ASSERT_EQ(foot.lock.state, FootLockState::kLocked);
  EXPECT_NEAR(horizontal(foot.goal, glm::vec3(0.0f)), 0.0f, 1e-6f);
  // The swing: 29 frames of progress 0..1, the clip's toe 2 cm per frame ahead and 5 cm up.
  auto swing_toe = [](int k) {
    return glm::vec3(0.2f + 0.02f * (k + 1), 0.03f + 0.05f * std::sin(3.14159265f * k / 29.0f),
                     0.0f);
  };
  // At release the offset is the drawn toe minus the clip's: 0.22 m horizontally, -1 cm up.
  // Shed as a smoothstep of the progress (slope at most 1.5), it adds at most 1.5 * 0.22 / 29
  // m per frame horizontally to the clip's own motion; vertically the 1 cm is taken at once but
  // not in one frame (at most half of it per frame).
  const float off_xz = horizontal(foot.goal, swing_toe(0));
  ASSERT_NEAR(off_xz, 0.22f, 1e-5f);
  glm::vec3 prev = foot.goal, prev_anim = foot.anim;
  for (int k = 0; k <= 29; ++k) {
    const glm::vec3 a = swing_toe(k);
    const glm::vec3 g = foot.step(a, false, false, k / 29.0f);
    if (k == 0) {
      EXPECT_EQ(foot.lock.state, FootLockState::kReleasing);
      EXPECT_LT(horizontal(g, prev), 0.5f * horizontal(a, prev_anim))
          << "the release sets off from rest, not at the clip's speed";
    }
    // The clip's own step, the shed's (at most 1.5 * 0.22 / 29 m), and the carried rest's
    // catching up (a critically damped spring overshoots by at most e^-2 of its start speed).
    EXPECT_LE(horizontal(g, prev), horizontal(a, prev_anim) + 1.5f * off_xz / 29.0f +
                                       0.14f * horizontal(a, prev_anim) + 1e-5f)
        << k;
    EXPECT_LE(std::abs((g.y - prev.y) - (a.y - prev_anim.y)), 0.005f) << k;
    prev = g;
    prev_anim = a;
  }
  // Progress 1: the clip's toe, and free, but for what is left of the rest it set off from: the
  // carried 1.2 m/s (the clip's step) on a critically damped spring of lock_release_s's halflife,
  // v0 t e^{-y t} after the release's 30 frames (about 2 mm), which goes on decaying as the free
  // foot's offset: no jump as it turns free.
  const FootLockParams fp;
  const double y = 2.0 * std::log(2.0) / fp.carry_halflife_s, t = 30.0 * kDt;
  const double left = 1.2 * t * std::exp(-y * t);
  EXPECT_NEAR(horizontal(prev, swing_toe(29)), left, 1e-4);
  EXPECT_NEAR(prev.y, swing_toe(29).y, 1e-4f);
  EXPECT_EQ(foot.lock.state, FootLockState::kFree);
  const glm::vec3 after = foot.step(swing_toe(30), false, false, 0.0f);
  EXPECT_LT(glm::length(after - swing_toe(30)), left);
  EXPECT_LT(horizontal(after, prev), horizontal(swing_toe(30), swing_toe(29)) + 0.001f);
}

TEST(FootLock, ReleasedAboveAVerticallyStillClipToeStillLandsOnIt) {
  // Pinned on the floor while the clip's toe sinks 1 mm per frame to 1 cm below it and stays
  // there: released on a frame where the clip's toe moves only forward, the drawn toe is 1 cm
  // above the clip's. The swing (progress k / 20) lifts the clip's toe 5 cm and lands it 1 cm
  // above the floor (2 cm above where it left). By landing the goal must be the clip's toe: the
  // free foot of the next frame is drawn there, so anything else is a drop the floor clamp of
  // the caller does not hide.
  constexpr float kSunk = kFloor - 0.01f;
  Foot foot;
  foot.step({0.0f, kFloor, 0.0f}, true, true);
  for (int f = 1; f <= 12; ++f) {
    foot.step({0.0f, f >= 10 ? kSunk : kFloor - 0.001f * f, 0.0f}, false, true);
  }
  ASSERT_NEAR(foot.goal.y, kFloor, 1e-6f);
  auto swing_toe = [](int k) {
    return glm::vec3(0.05f * (k + 1),
                     kSunk + 0.05f * std::sin(3.14159265f * k / 20.0f) + 0.001f * k, 0.0f);
  };
  for (int k = 0; k <= 20; ++k) foot.step(swing_toe(k), false, false, k / 20.0f);
  EXPECT_NEAR(foot.goal.y, swing_toe(20).y, 1e-3f);
  // Horizontally at the clip's toe but for what is left of the rest it set off from (the clip's
  // 3 m/s carried on a critically damped spring, v0 t e^{-y t} after 21 frames: about 2 cm; it
  // goes on decaying as the free foot's offset).
  const FootLockParams fp;
  const double y = 2.0 * std::log(2.0) / fp.carry_halflife_s, t = 21.0 * kDt;
  EXPECT_NEAR(horizontal(foot.goal, swing_toe(20)), 3.0 * t * std::exp(-y * t), 1e-3);
  const glm::vec3 landed = foot.goal;
  const glm::vec3 next = foot.step(swing_toe(20), false, false, 0.0f);
  EXPECT_NEAR(std::max(next.y, kFloor), std::max(landed.y, kFloor), 1e-3f);
}

TEST(FootLock, ReplantingStepLiftsFirstAndLandsOnTheClipsToe) {
  Foot foot;
  const glm::vec3 from(0.0f, kFloor, 0.0f), to(0.3f, kFloor, 0.1f);
  foot.step(from, true, true);
  foot.lock = start_foot_step(foot.lock, foot.goal);
  ASSERT_EQ(foot.lock.state, FootLockState::kStepping);
  const float h = foot.params.step_height_m, T = foot.params.step_time_s;
  float peak = -1.0f;
  glm::vec3 prev = from;
  int k = 1;
  for (; k <= 30; ++k) {
    const glm::vec3 g = foot.step(to, false, true);
    const float t = k * kDt;
    if (k == 1) {
      // Zero speed at the start: a sin^2 rise moves h * (pi t / T)^2 = 1.1 mm in the first frame,
      // a constant speed would move about h * pi / T * dt = 7.5 mm.
      EXPECT_LT(glm::length(g - from), 0.002f);
    }
    // The first fifth of the step only lifts (t <= 0.07 s: frames 1-4); the last fifth only sets
    // down (t >= 0.28 s: frame 17 on).
    if (t <= 0.2f * T - 1e-4f) {
      EXPECT_NEAR(horizontal(g, from), 0.0f, 1e-6f) << k;
    }
    if (k == 4) {
      EXPECT_GT(g.y, from.y + 0.01f);  // h sin^2(pi 4/21) = 1.6 cm
    }
    if (t >= 0.8f * T + 1e-4f) {
      EXPECT_NEAR(horizontal(g, to), 0.0f, 1e-6f) << k;
    }
    EXPECT_LE(horizontal(g, to), horizontal(prev, to) + 1e-6f) << "moves towards the toe: " << k;
    peak = std::max(peak, g.y);
    prev = g;
    if (foot.lock.state == FootLockState::kLocked) break;
  }
  // 0.35 s at 60 Hz: 21 frames (22 if the float sum of dt falls short of 0.35).
  EXPECT_GE(k, 21);
  EXPECT_LE(k, 22);
  ASSERT_EQ(foot.lock.state, FootLockState::kLocked);
  EXPECT_NEAR(glm::length(prev - to), 0.0f, 1e-6f);
  // Both ends on the floor: the peak is h above it, sampled at u = 10/21 or 11/21 where
  // sin^2(pi u) = 0.9944.
  EXPECT_GE(peak, kFloor + 0.99f * h);
  EXPECT_LE(peak, kFloor + h + 1e-6f);
  // Locked where it landed while the clip's toe moves on.
  const glm::vec3 g = foot.step(to + glm::vec3(0.05f, 0.0f, 0.0f), false, true);
  EXPECT_NEAR(horizontal(g, to), 0.0f, 1e-6f);
}

TEST(FootLock, StepBecomesAReleaseWhenTheClipsLiftTheFoot) {
  Foot foot;
  const glm::vec3 to(0.3f, kFloor, 0.0f);
  foot.step(glm::vec3(0.0f, kFloor, 0.0f), true, true);
  foot.lock = start_foot_step(foot.lock, foot.goal);
  glm::vec3 before = foot.goal;
  for (int k = 1; k <= 8; ++k) {
    before = foot.goal;
    foot.step(to, false, true);
  }
  const glm::vec3 last = foot.goal;
  const float last_move = glm::length(last - before);
  const glm::vec3 g = foot.step(to + glm::vec3(0.02f, 0.01f, 0.0f), false, false, 0.3f);
  EXPECT_EQ(foot.lock.state, FootLockState::kReleasing);
  EXPECT_LE(glm::length(g - last), last_move + 0.01f);
  glm::vec3 a;
  for (int k = 1; k <= 10; ++k) {
    a = to + glm::vec3(0.02f * (k + 1), 0.01f, 0.0f);
    foot.step(a, false, false, k == 10 ? 1.0f : 0.3f + 0.07f * k);  // lands at progress 1
  }
  EXPECT_EQ(foot.lock.state, FootLockState::kFree);
  // At the clip's toe but for what is left of the step's carried velocity (about a centimetre
  // after ten frames of lock_release_s's halflife), which keeps decaying there: no jump when it
  // turns free.
  EXPECT_LT(horizontal(foot.goal, a), 0.015f);
  const float left = horizontal(foot.goal, a);
  for (int k = 0; k < 60; ++k) foot.step(a, false, false, 1.0f);
  EXPECT_LT(horizontal(foot.goal, a), 0.01f * left + 1e-5f);
}

TEST(FootLock, FreshFrameResetsEverything) {
  Foot foot = pinned_then_held();
  foot.step({0.5f, 0.1f, 0.0f}, false, false, 0.2f);  // releasing, with a 0.3 m offset
  ASSERT_EQ(foot.lock.state, FootLockState::kReleasing);
  foot.started = false;  // the next frame is fresh
  const glm::vec3 a(5.0f, 0.3f, -2.0f);
  EXPECT_EQ(foot.step(a, false, false), a);
  EXPECT_EQ(foot.lock.state, FootLockState::kFree);
  EXPECT_EQ(foot.lock.offset, glm::vec3(0.0f));
  EXPECT_EQ(foot.lock.offset_vel, glm::vec3(0.0f));
  EXPECT_EQ(foot.lock.shed, 0.0f);
  EXPECT_EQ(foot.lock.timer_s, 0.0f);
  // Fresh and planted: locked at the clip's toe itself (nothing was drawn before).
  foot.started = false;
  const glm::vec3 b(-1.0f, 0.025f, 3.0f);
  EXPECT_EQ(foot.step(b, true, true), b);
  EXPECT_EQ(foot.lock.state, FootLockState::kLocked);
  EXPECT_EQ(foot.lock.target, b);
}

TEST(FootLock, GoalIsNeverNaN) {
  std::mt19937 rng(1234);
  std::uniform_real_distribution<float> pos(-10.0f, 10.0f), height(-1.0f, 2.0f), unit(0.0f, 1.0f);
  for (int run = 0; run < 200; ++run) {
    FootLock lock;
    FootLockParams params;
    const float dt = 1e-4f + 0.1f * unit(rng);
    glm::vec3 anim(0.0f), goal(0.0f);
    for (int f = 0; f < 200; ++f) {
      FootLockInput in;
      in.anim_toe_prev = anim;
      in.drawn_toe_prev = unit(rng) < 0.9f ? goal : glm::vec3(pos(rng), height(rng), pos(rng));
      anim = unit(rng) < 0.1f
                 ? glm::vec3(pos(rng), height(rng), pos(rng))
                 : anim + 0.05f * glm::vec3(unit(rng) - 0.5f, unit(rng) - 0.5f, unit(rng) - 0.5f);
      in.anim_toe = anim;
      in.fresh = f == 0 || unit(rng) < 0.01f;
      in.plant = unit(rng) < 0.3f;
      in.hold = unit(rng) < 0.6f;
      in.swing_progress = -0.5f + 2.0f * unit(rng);
      in.other_locked = unit(rng) < 0.5f;
      in.floor_toe_m = 0.2f * (unit(rng) - 0.5f);
      if (unit(rng) < 0.03f) lock = start_foot_step(lock, goal);
      if (unit(rng) < 0.03f) {
        lock = release_foot_lock(lock, goal, glm::vec3(pos(rng)), anim, glm::vec3(0));
      }
      const FootLockStep next = step_foot_lock(lock, in, params, dt);
      lock = next.state;
      goal = next.goal;
      ASSERT_TRUE(std::isfinite(goal.x) && std::isfinite(goal.y) && std::isfinite(goal.z))
          << "run " << run << " frame " << f;
    }
  }
}

// A body turning on the spot carries the clip's toe sideways at 1.5 m/s through a whole
// re-planting step: the foot follows it while carried, and comes down on one spot.
TEST(FootLock, StepSetsTheFootDownWhereItWasCarried) {
  Foot foot;
  glm::vec3 anim(0.0f, kFloor, 0.0f);
  foot.step(anim, true, true);
  ASSERT_EQ(foot.lock.state, FootLockState::kLocked);
  foot.lock = start_foot_step(foot.lock, foot.goal);
  const float speed = 1.5f;  // [m/s] of the clip's toe
  int lowering = 0;
  glm::vec3 set_down(0.0f);
  for (int k = 1; k <= 40 && foot.lock.state == FootLockState::kStepping; ++k) {
    const glm::vec3 prev_goal = foot.goal;
    anim.x += speed * kDt;
    const glm::vec3 goal = foot.step(anim, false, true);
    const float t = k * kDt;
    if (t >= (1.0f - 0.2f) * foot.params.step_time_s + kDt) {
      // The last fifth only sets the foot down: no horizontal motion at all.
      if (lowering++ == 0) set_down = prev_goal;
      EXPECT_NEAR(horizontal(goal, set_down), 0.0f, 1e-6f) << k;
    }
  }
  ASSERT_EQ(foot.lock.state, FootLockState::kLocked);
  EXPECT_GE(lowering, 3);
  // It came down where it was carried to, behind the clip's toe, which moved on.
  const glm::vec3 landed = foot.goal;
  EXPECT_GT(horizontal(anim, landed), 0.05f);
  // Pinned there on the next frame.
  anim.x += speed * kDt;
  EXPECT_NEAR(horizontal(foot.step(anim, false, true), landed), 0.0f, 1e-6f);
}

// A re-planting step while the clip's foot jumps back under it mid-carry, as it does when a walk
// fades in over a standing blend (4.6 cm a frame in a DetourCrowd jam with the CMU clips): the step
// still follows most of it, but its goal never turns harder than the step itself does
// toward a clip foot that moves steadily. Aimed at the clip's foot directly, the step's velocity
// reversed in a frame and the ankle snapped.
TEST(FootLock, StepAimsAtAClipFootThatJumpsWithoutSnapping) {
  // The largest horizontal acceleration of the goal over the step, and where the foot landed.
  auto run = [](float jump_m) {
    Foot foot;
    glm::vec3 anim(0.0f, kFloor, 0.0f);
    foot.step(anim, true, true);
    foot.lock = start_foot_step(foot.lock, glm::vec3(-0.3f, kFloor, 0.0f));
    foot.goal = glm::vec3(-0.3f, kFloor, 0.0f);
    std::vector<glm::vec3> goals{foot.goal};
    for (int k = 1; k <= 40 && foot.lock.state == FootLockState::kStepping; ++k) {
      anim.x += 0.3f * kDt;                            // the body drifts on at 0.3 m/s
      if (k >= 12 && k < 15) anim.x -= jump_m / 3.0f;  // the blend moves the clip's foot back
      goals.push_back(foot.step(anim, false, true, 0.0f, false, /*still_speed=*/0.2f));
    }
    float most = 0.0f;
    for (size_t i = 2; i < goals.size(); ++i) {
      const glm::vec3 a = (goals[i] - 2.0f * goals[i - 1] + goals[i - 2]) / (kDt * kDt);
      most = std::max(most, std::hypot(a.x, a.z));
    }
    return std::pair{most, foot.lock.state == FootLockState::kLocked ? foot.goal.x - anim.x : 1e9f};
  };
  const auto [steady_accel, steady_miss] = run(0.0f);
  const auto [jump_accel, jump_miss] = run(0.14f);
  EXPECT_NEAR(jump_miss, steady_miss, 0.25f * 0.14f);  // most of the jump followed
  EXPECT_LE(jump_accel, 1.5f * steady_accel) << steady_accel;
}

// Released 0.75 m from a clip toe that stands still (a foot left behind in a jam): with the
// clips' swing speed given, the foot is carried at no more than that speed; without it, the
// release's shortest time (twice the halflife) would carry it at several times that.
TEST(FootLock, ReleasedFootIsCarriedNoFasterThanTheClipsSwing) {
  for (const float swing_speed : {0.0f, 3.0f}) {
    Foot foot;
    foot.params.swing_speed_m_s = swing_speed;
    const glm::vec3 pinned(0.0f, kFloor, 0.0f), anim(0.75f, kFloor, 0.0f);
    foot.step(pinned, true, true);
    foot.lock = release_foot_lock(foot.lock, foot.goal, glm::vec3(0.0f), anim, glm::vec3(0.0f));
    foot.anim = anim;  // the clip's toe stands there from now on
    float fastest = 0.0f;
    int frames = 0;
    for (int k = 1; k <= 120 && foot.lock.state == FootLockState::kReleasing; ++k, ++frames) {
      const glm::vec3 prev = foot.goal;
      // A short swing of the clips (0.1 s, as at a crawl in a jam); their toe stays put.
      const glm::vec3 goal = foot.step(anim, false, false, std::min(1.0f, k / 6.0f));
      fastest = std::max(fastest, horizontal(goal, prev) / kDt);
    }
    EXPECT_NEAR(horizontal(foot.goal, anim), 0.0f, 1e-4f);
    if (swing_speed > 0.0f) {
      EXPECT_LE(fastest, swing_speed * 1.02f);
      // 0.75 m at a smoothstep peaking at 3 m/s takes 1.5 * 0.75 / 3 = 0.375 s.
      EXPECT_GE(frames, static_cast<int>(0.375f / kDt) - 1);
    } else {
      EXPECT_GT(fastest, 6.0f) << "the unlimited release is fast: the test would catch a drag";
    }
  }
}

// The foot locks measure ground distances with ground_length in place of std::hypot: the same
// bits for every finite pair, small, large and subnormal alike.
TEST(FootLock, GroundLengthIsHypotToTheBit) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> mantissa(-1.0f, 1.0f);
  std::uniform_int_distribution<int> exponent(-140, 127);
  for (int i = 0; i < 200000; ++i) {
    const float x = std::ldexp(mantissa(rng), exponent(rng));
    const float z = i % 3 == 0 ? std::ldexp(mantissa(rng), exponent(rng)) : mantissa(rng);
    const float want = std::hypot(x, z), got = ground_length(x, z);
    ASSERT_EQ(std::memcmp(&want, &got, sizeof(float)), 0) << x << " " << z;
  }
}

}  // namespace
}  // namespace gk
