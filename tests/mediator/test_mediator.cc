// The mediator on scripted crowds with the built-in clips: planted feet, rate limits, torsion
// limit, facing, feedback and robustness, each measured with the METRICS.md definitions.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <numbers>

#include <gtest/gtest.h>

#include "animation/pose_jobs.h"
#include "mediator/mediator_passes.h"
#include "mediator/springs.h"
#include "tests/mediator/mediator_fixture.h"
#include "tests/mediator/scripted_crowd.h"
#include "pipeline/crowd_pipeline.h"

namespace gk {
namespace {

using test::builtin_library;
using test::run_scripted;
using test::Script;
using test::straight;

MediatorParams with_mode(MediatorMode mode) {
  MediatorParams p;
  p.mode = mode;
  return p;
}

// Speeds between the clips' own speeds, where a single clip at its native rate must skate.
TEST(Mediator, ApmPlantsFeetWhereNaiveSkates) {
  for (float speed : {1.05f, 2.1f}) {
    std::vector<Script> s;
    for (int i = 0; i < 6; ++i) s.push_back(straight({2.0f * i, 0.0f}, {0.0f, speed}));
    const auto apm = run_scripted(builtin_library(), s, with_mode(MediatorMode::kApm));
    const auto naive = run_scripted(builtin_library(), s, with_mode(MediatorMode::kNaive));
    EXPECT_LE(apm.report.slide.mean_cm_s, 2.0f) << speed;
    EXPECT_LE(apm.report.slide.skate_ratio, 0.005f) << speed;
    EXPECT_GE(naive.report.slide.mean_cm_s, 10.0f * apm.report.slide.mean_cm_s) << speed;
    EXPECT_GT(apm.report.slide.num_samples, 1000) << speed;  // the feet really were down
  }
}

TEST(Mediator, PlaybackRateStaysWithinLimitsOverASpeedRamp) {
  // 0 -> 5 m/s over 10 s, beyond the fastest clip: rate limits hold, feedback caps the speed.
  std::vector<Script> s{
      {{0, 0}, [](double t) { return glm::vec2(0.0f, 0.5f * float(t)); }, nullptr}};
  MediatorParams p;
  const auto r = run_scripted(builtin_library(), s, p, 600);
  EXPECT_EQ(r.report.playback_outside_limits, 0.0);
  EXPECT_GE(r.report.playback_rate.min, p.min_playback_rate - 1e-4);
  EXPECT_LE(r.report.playback_rate.max, p.max_playback_rate + 1e-4);
  EXPECT_EQ(r.report.pop_count, 0);
  // 3.6 m/s run x 1.35 rate x 1.2 warp = 5.83 m/s: 5 m/s is deliverable, so no feedback.
  EXPECT_FALSE(r.report.feedback_speed_change.has_value());
}

// Below the slowest clip a walker keeps the walk ratio (GAIT.md: step length over cadence about
// constant), so at a share x of that clip's speed both the cadence (the playback rate, x over the
// gait weight) and the stride (the gait weight, the rest standing) are about sqrt(x) of the
// clip's own, the cadence no slower than min_playback_rate (then the stride shortens alone) nor
// than an agent about to stop holds it.
TEST(Mediator, BelowTheSlowestClipCadenceAndStrideShareTheSlowing) {
  const LocomotionLibrary& lib = builtin_library();
  const MediatorParams p;
  const int slow = lib.groups[lib.forward_group].clips.front();
  const float first = lib.clips[slow].speed_m_s;
  std::vector<float> w(lib.clips.size());
  for (const float x : {0.9f, 0.64f, 0.5f, 0.3f, 0.15f}) {
    choose_clip_weights(lib, p, x * first, 0.0f, w);
    const float gait = w[slow];
    EXPECT_NEAR(gait + w[lib.idle], 1.0f, 1e-5f) << x;
    const float cadence = x / gait;  // the playback rate the blend's native speed asks for
    EXPECT_NEAR(cadence, std::max(std::sqrt(x), p.min_playback_rate), 1e-4f) << x;
    if (std::sqrt(x) >= p.min_playback_rate) {
      EXPECT_NEAR(gait, std::sqrt(x), 1e-4f) << x;
    }
    // An agent about to stop that walked at cadence 0.95 keeps it.
    choose_clip_weights(lib, p, x * first, 0.0f, w, 0.95f);
    EXPECT_NEAR(x / w[slow], 0.95f, 1e-4f) << x;
  }
}

// Agents that stand, then set off in every direction (a turn on the spot re-plants a foot while
// the clips still stand): the clips' first step waits until a re-planting foot is down, so a
// stepping foot always has the other one pinned, and the re-planting step is never released while
// the other foot is in the air: never both feet in the air at a walk.
TEST(Mediator, SettingOffFromStandingNeverLiftsBothFeet) {
  constexpr float kDt = 1.0f / 60.0f;
  std::vector<Script> s;
  for (int i = 0; i < 8; ++i) {
    const float a = 0.25f * std::numbers::pi_v<float> * static_cast<float>(i);
    const glm::vec2 dir(std::sin(a), std::cos(a));
    s.push_back({{3.0f * i, 0.0f}, [dir](double t) {
                   const double u = std::clamp((t - 1.0) / 1.0, 0.0, 1.0);
                   return static_cast<float>(1.3 * u * u * (3.0 - 2.0 * u)) * dir;
                 },
                 nullptr});
  }
  test::ScriptedCrowd crowd(std::move(s));
  CrowdPipeline pipeline(builtin_library(), MediatorParams{},
                         test::test_pipeline_options(crowd.capacity(), kDt));
  int steps = 0;
  for (int f = 0; f < 240; ++f) {
    ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
    const AnimationPlans& pl = pipeline.mediator().plans();
    const FootLocks& locks = pipeline.poses().foot_locks();
    for (size_t i = 0; i < crowd.capacity(); ++i) {
      const size_t slot = static_cast<size_t>(pl.slot_of_agent[i]);
      const FootLockState l = locks.lock[slot * 2].state, r = locks.lock[slot * 2 + 1].state;
      for (const auto& [one, other] : {std::pair{l, r}, std::pair{r, l}}) {
        if (one != FootLockState::kStepping) continue;
        ++steps;
        EXPECT_EQ(other, FootLockState::kLocked) << "agent " << i << " frame " << f;
      }
    }
  }
  EXPECT_GT(steps, 0) << "no agent re-planted a foot: the test saw nothing";
}

// stand_through_jitter (a source that takes no feedback): one agent's standing flag and p per
// frame, with the gate on or off, at frame time dt, optionally far from the LOD focus (planned
// every 8th frame) and with a hook before each step.
struct StandingRun {
  std::vector<uint8_t> walking;
  std::vector<glm::vec2> p;
};
StandingRun run_standing(bool gate, float dt, std::function<glm::vec2(double)> vel, double t_end,
                         bool lod_far = false,
                         std::function<void(CrowdPipeline&, int)> hook = nullptr,
                         glm::vec2 start = {2.0f, 1.0f}) {
  std::vector<Script> s{{start, std::move(vel), [](double, glm::vec2) { return 0.0f; }}};
  test::ScriptedCrowd crowd(std::move(s));
  MediatorParams p;
  p.stand_through_jitter = gate;
  CrowdPipeline pipeline(builtin_library(), p, test::test_pipeline_options(1, dt));
  if (lod_far) {
    LodParams lp;
    lp.enabled = true;
    lp.focus = glm::vec2(1000.0f, 1000.0f);
    EXPECT_TRUE(pipeline.set_lod(lp).ok());
  }
  StandingRun out;
  const int frames = static_cast<int>(std::lround(t_end / dt));
  for (int f = 0; f < frames; ++f) {
    if (hook) hook(pipeline, f);
    EXPECT_TRUE(pipeline.step(crowd, dt).ok());
    const AnimationPlans& pl = pipeline.plans();
    out.walking.push_back(pl.standing[static_cast<size_t>(pl.slot_of_agent[0])] == 0);
    out.p.push_back(pipeline.frame().positions[0]);
  }
  return out;
}
// The first frame from `from` on where the agent walks (-1: never).
int first_walking(const StandingRun& r, int from) {
  for (size_t f = static_cast<size_t>(from); f < r.walking.size(); ++f) {
    if (r.walking[f]) return static_cast<int>(f);
  }
  return -1;
}
double ease(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * (3.0 - 2.0 * u);
}
// A wobble: 3 cm out and back in 0.8 s (at up to 0.12 m/s), each time in another direction.
glm::vec2 wobble(double t) {
  const int k = static_cast<int>(t / 0.4);
  const float dir = 2.4f * static_cast<float>(k / 2);
  const float peak = 0.03f * std::numbers::pi_v<float> / (2.0f * 0.4f);
  const float speed =
      (k % 2 == 0 ? peak : -peak) * static_cast<float>(std::sin(std::numbers::pi * (t / 0.4 - k)));
  return speed * glm::vec2(std::sin(dir), std::cos(dir));
}

// A clean track's jitter is about nil: a walker who stops, waits and sets off again is walking on
// the same frame with the gate as without, at 60 and 30 fps, and planned every 8th frame (LOD).
TEST(Mediator, StandingThroughJitterKeepsCleanStartsOnTime) {
  for (const float dt : {1.0f / 60.0f, 1.0f / 30.0f}) {
    for (const double pause : {0.3, 1.0, 2.0}) {
      for (const bool lod : {false, true}) {
        auto vel = [pause](double t) {
          double v = 1.3;
          if (t >= 2.0 && t < 3.0) v = 1.3 * (1.0 - ease(t - 2.0));
          if (t >= 3.0) v = t < 3.0 + pause ? 0.0 : 1.3 * ease(t - 3.0 - pause);
          return glm::vec2(0.0f, static_cast<float>(v));
        };
        const int restart = static_cast<int>(std::lround((3.0 + pause) / dt));
        const StandingRun on = run_standing(true, dt, vel, 3.0 + pause + 3.0, lod);
        const StandingRun off = run_standing(false, dt, vel, 3.0 + pause + 3.0, lod);
        const std::string what =
            "dt " + std::to_string(dt) + " pause " + std::to_string(pause) + (lod ? " lod" : "");
        ASSERT_GE(first_walking(off, restart), restart) << what;
        EXPECT_EQ(first_walking(on, restart), first_walking(off, restart)) << what;
      }
    }
  }
  // A new agent standing still starts on time too.
  auto start = [](double t) { return glm::vec2(0.0f, static_cast<float>(1.3 * ease(t - 2.0))); };
  const StandingRun on = run_standing(true, 1.0f / 60.0f, start, 5.0);
  const StandingRun off = run_standing(false, 1.0f / 60.0f, start, 5.0);
  EXPECT_GT(first_walking(off, 1), 100) << "it stood for two seconds first";
  EXPECT_EQ(first_walking(on, 1), first_walking(off, 1));
}

// A clean pedestrian who stands, shuffles 8 cm and stops again, then sets off: the shuffle is not
// taken for jitter (no delay against the gate off).
TEST(Mediator, StandingThroughJitterDoesNotTakeAShuffleForJitter) {
  constexpr float kDt = 1.0f / 60.0f;
  auto vel = [](double t) {
    double v = 0.0;
    if (t >= 1.0 && t < 1.4) v = 0.2 * std::sin(std::numbers::pi * (t - 1.0) / 0.4);  // ~5 cm
    if (t >= 2.5) v = 1.3 * ease(t - 2.5);
    return glm::vec2(0.0f, static_cast<float>(v));
  };
  const StandingRun on = run_standing(true, kDt, vel, 5.0);
  const StandingRun off = run_standing(false, kDt, vel, 5.0);
  const int from = static_cast<int>(2.5 / kDt);
  ASSERT_GE(first_walking(off, from), from);
  EXPECT_EQ(first_walking(on, from), first_walking(off, from));
}

// One whose p wobbles about where it stands stays standing once it has shown its jitter (without
// the gate it walks on many frames); when it then walks off slowly (0.3 m/s, still wobbling) it is
// let go within a second, before p has left where it stood by more than a re-planting step.
TEST(Mediator, StandingThroughJitterHoldsAWobbleAndLetsASlowStartGo) {
  constexpr float kDt = 1.0f / 60.0f;
  const StandingRun on = run_standing(true, kDt, wobble, 5.0);
  const StandingRun off = run_standing(false, kDt, wobble, 5.0);
  int walking_on = 0, walking_off = 0;
  for (size_t f = 150; f < on.walking.size(); ++f) {  // after the first few wobbles
    walking_on += on.walking[f];
    walking_off += off.walking[f];
  }
  EXPECT_EQ(walking_on, 0) << "held standing once it has shown its jitter";
  EXPECT_GT(walking_off, 30) << "without, it walks on many of those frames";

  auto walk_off = [](double t) {
    glm::vec2 v = wobble(t);
    if (t >= 4.0) v.y += static_cast<float>(0.3 * ease((t - 4.0) / 0.5));
    return v;
  };
  const StandingRun slow = run_standing(true, kDt, walk_off, 8.0);
  const int from = static_cast<int>(4.0 / kDt);
  const int walks = first_walking(slow, from);
  ASSERT_GE(walks, from);
  EXPECT_LT(walks - from, static_cast<int>(1.0 / kDt)) << "let go within a second";
  const MediatorParams defaults;
  for (size_t f = static_cast<size_t>(from); f < static_cast<size_t>(walks); ++f) {
    EXPECT_LE(glm::length(slow.p[f] - slow.p[static_cast<size_t>(from)]),
              defaults.idle_step_distance_m + 0.03f)
        << "frame " << f;
  }
}

// Switched from naive to APM while it stands (the panel's mode), it knows nothing of where it
// stood before: its start is on time, as when it had been in APM all along. It stands 5 cm from
// the origin, where a slot's state starts: taken for where it stood, that distance would pass for
// jitter and hold the start.
TEST(Mediator, StandingThroughJitterStartsAfreshWhenTheGateComesOn) {
  constexpr float kDt = 1.0f / 60.0f;
  auto start = [](double t) { return glm::vec2(0.0f, static_cast<float>(1.3 * ease(t - 4.0))); };
  auto switched = [](CrowdPipeline& pipeline, int f) {
    if (f != 0 && f != 120) return;
    MediatorParams p = pipeline.params();
    p.mode = f == 0 ? MediatorMode::kNaive : MediatorMode::kApm;
    pipeline.set_params(p);
  };
  const glm::vec2 at(0.05f, 0.0f);
  const StandingRun sw = run_standing(true, kDt, start, 7.0, false, switched, at);
  const StandingRun apm = run_standing(true, kDt, start, 7.0, false, nullptr, at);
  const int from = static_cast<int>(4.0 / kDt);
  ASSERT_GE(first_walking(apm, from), from);
  EXPECT_EQ(first_walking(sw, from), first_walking(apm, from));
}

TEST(Mediator, TorsionNeverExceedsTheLimit) {
  // theta sweeps all the way round while walking: the twist must clamp at the limit.
  MediatorParams p;
  p.torsion_limit_deg = 40.0f;
  std::vector<Script> s{{{0, 0},
                         [](double) { return glm::vec2(0.0f, 1.3f); },
                         [](double t, glm::vec2) { return float(0.8 * t); }}};
  const auto r = run_scripted(builtin_library(), s, p);
  EXPECT_LE(r.report.torsion_deg.max, 40.5);
  EXPECT_GT(r.report.torsion_deg.max, 20.0);  // it did twist
}

TEST(Mediator, UpperBodyFacesThetaWithinTheLimit) {
  // Looking 35 degrees to the left of the walking direction, within the 60 degree limit.
  const float look = 35.0f * std::numbers::pi_v<float> / 180.0f;
  std::vector<Script> s;
  for (int i = 0; i < 4; ++i) {
    s.push_back({{2.0f * i, 0},
                 [](double) { return glm::vec2(0.0f, 1.2f); },
                 [look](double, glm::vec2) { return look; }});
  }
  const auto apm = run_scripted(builtin_library(), s, MediatorParams{});
  EXPECT_LE(apm.report.facing_error_deg.p95, 10.0);
  const auto naive = run_scripted(builtin_library(), s, with_mode(MediatorMode::kNaive));
  EXPECT_GE(naive.report.facing_error_deg.mean, 25.0);  // naive faces v, not theta
}

TEST(Mediator, RootFollowsTheSimulator) {
  std::vector<Script> s{straight({0, 0}, {0.9f, 0.9f})};
  const auto r = run_scripted(builtin_library(), s, MediatorParams{});
  EXPECT_LE(r.report.root_error_cm.mean, 3.0);
  EXPECT_LE(r.report.root_error_cm.max, 10.0);
  EXPECT_LE(r.report.heading_error_deg.p95, 15.0);
}

// A captured gait travels a few degrees off the way its body faces (16_36's jog loop: -3.4 deg):
// the lower body faces that much the other way, so the legs carry the body along v rather than
// the clip's drift showing as a constant heading error.
TEST(Mediator, CapturedGaitTravelsAlongVNotAlongItsDrift) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_36_run_jog_mrl30.bvh");
  auto lib = test::load_data_library({"clips/bvh/more/cmu_16_36_run_jog_mrl30.bvh"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  float drift = 0.0f;
  for (const LocomotionClip& c : lib->clips) {
    if (c.gait) drift = std::max(drift, std::abs(c.direction_offset_rad));
  }
  ASSERT_GT(glm::degrees(drift), 2.0f);  // the case this test is about
  constexpr float kDt = 1.0f / 60.0f;
  test::ScriptedCrowd crowd({straight({0, 0}, {0.0f, 2.8f})});
  CrowdPipeline pipeline(*lib, MediatorParams{}, test::test_pipeline_options(1, kDt));
  double off_deg = 0.0;
  int n = 0;
  for (int f = 0; f < 240; ++f) {
    ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
    const AnimationPlans& pl = pipeline.mediator().plans();
    if (f < 60) continue;  // the lower body has turned to its walk
    off_deg += std::abs(glm::degrees(wrap_pi(pl.travel_yaw[pl.slot_of_agent[0]])));  // v is +z
    ++n;
  }
  EXPECT_LE(off_deg / n, 0.1 * glm::degrees(drift));
}

TEST(Mediator, FeedsBackTheSpeedItCanDeliver) {
  // 9 m/s is beyond anything the clips can do: the built-in run's 3.6 m/s at the fastest rate
  // (1.35), with the stride stretch allowed (none by default, or 20%): 4.86 or 5.83 m/s.
  for (const float warp : {0.0f, 0.2f}) {
    std::vector<Script> s{straight({0, 0}, {0.0f, 9.0f})};
    MediatorParams p;
    p.max_stride_warp = warp;
    const auto r = run_scripted(builtin_library(), s, p, 120, /*honour=*/true);
    ASSERT_TRUE(r.report.feedback_speed_change.has_value());
    EXPECT_NEAR(*r.report.feedback_speed_change, 1.0 - 3.6 * 1.35 * (1.0 + warp) / 9.0, 0.01)
        << warp;
    EXPECT_EQ(r.feedback_frames, 120);
  }
}

// A simulator with inertia that honours feedback: each frame its velocity moves from the one fed
// back toward the desired one with time constant kTau, and it walks with the velocity fed back.
struct TurningRun {
  int feedback_frames = 0;   // frames whose velocity was fed back changed
  int frames_to_turn = -1;   // until the velocity fed back is within 10 degrees of the desired one
  float max_off_deg = 0.0f;  // largest angle between the velocity fed back and the lower body
  glm::vec2 position{0.0f};
};
TurningRun run_turn(const LocomotionLibrary& lib, const MediatorParams& p, float turn_deg,
                    float look_deg) {
  constexpr float kDt = 1.0f / 60.0f, kTau = 0.1f, kSpeed = 1.3f;
  Mediator m(lib, p, 1);
  const uint32_t id = 5;
  glm::vec2 pos(0.0f), vel(0.0f, kSpeed);
  TurningRun out;
  for (int f = 0; f < 180; ++f) {
    const float want = f < 60 ? 0.0f : glm::radians(turn_deg);
    const glm::vec2 desired = kSpeed * glm::vec2(std::sin(want), std::cos(want));
    vel += (desired - vel) * (kDt / kTau);
    const float theta = want + glm::radians(look_deg);
    EXPECT_TRUE(m.plan(AgentFrame{{&id, 1}, {&pos, 1}, {&vel, 1}, {&theta, 1}}, kDt,
                       FeedbackPolicy::kHonoured)
                    .ok());
    const FeedbackBuffers& fb = m.feedback();
    const float psi = m.plans().lower_yaw[m.plans().slot_of_agent[0]];
    if (fb.has_feedback[0] && glm::length(fb.velocities[0] - vel) > 1e-4f) {
      ++out.feedback_frames;  // the velocity was changed (theta may be fed back on its own)
      EXPECT_NEAR(glm::length(fb.velocities[0]), glm::length(vel), 1e-3f) << f;  // speed kept
      vel = fb.velocities[0];
    }
    const float off = std::abs(wrap_pi(std::atan2(vel.x, vel.y) - psi));
    out.max_off_deg = std::max(out.max_off_deg, glm::degrees(off));
    if (f >= 60 && out.frames_to_turn < 0 &&
        std::abs(wrap_pi(std::atan2(vel.x, vel.y) - want)) < glm::radians(10.0f)) {
      out.frames_to_turn = f - 60;
    }
    pos += vel * kDt;
  }
  out.position = pos;
  return out;
}

TEST(Mediator, FeedsBackAWalkingDirectionTheLegsCanTake) {
  // Forward clips only (like the mannequin and CMU sets): the legs walk where the lower body
  // faces, which turns at lower_turn_rate_deg_s. A sharp turn of the simulator's velocity is
  // held to within turn_feedback_deg of that facing, and the turn still completes at about the
  // legs' rate (135 degrees at 300 deg/s: 27 frames).
  const LocomotionLibrary lib = test::builtin_library_without({"strafe", "backward"});
  ASSERT_FALSE(lib.has_direction_clips());
  MediatorParams p;
  // The turn alone: this simulator regains speed after the turn faster than legs speed up
  // (FeedsBackAStartTheLegsCanMake), which would be fed back too.
  p.max_accel_m_s2 = 20.0f;
  const TurningRun r = run_turn(lib, p, 135.0f, 0.0f);
  EXPECT_GE(r.feedback_frames, 5);
  EXPECT_LE(r.max_off_deg, p.turn_feedback_deg + 0.1f);
  ASSERT_GE(r.frames_to_turn, 0);
  EXPECT_LE(r.frames_to_turn, 45);
  // Without the feedback the simulator turns faster than the legs.
  p.turn_feedback_deg = 180.0f;
  const TurningRun off = run_turn(lib, p, 135.0f, 0.0f);
  EXPECT_EQ(off.feedback_frames, 0);
  EXPECT_GE(off.max_off_deg, 40.0f);
}

// The lower body's turns speed up and slow down (lower_turn_accel_deg_s2): a simulator whose
// velocity zig-zags (a jam's agents are pushed one way, then the other) never makes the lower body
// reverse its turn in one frame, which snapped the knees around (limb pops); it still turns at up
// to lower_turn_rate_deg_s, and comes to rest on a turn's new heading without overshooting it.
struct YawTrace {
  std::vector<float> yaw;  // lower_yaw per frame [rad]
};
YawTrace zig_zag(const MediatorParams& p, int frames, int period, float swing_deg) {
  constexpr float kDt = 1.0f / 60.0f, kSpeed = 1.0f;
  const LocomotionLibrary lib = test::builtin_library_without({"strafe", "backward"});
  Mediator m(lib, p, 1);
  const uint32_t id = 3;
  glm::vec2 pos(0.0f);
  YawTrace out;
  for (int f = 0; f < frames; ++f) {
    const float dir = glm::radians(period > 0 && (f / period) % 2 ? swing_deg : 0.0f);
    const glm::vec2 vel = kSpeed * glm::vec2(std::sin(dir), std::cos(dir));
    const float theta = dir;
    EXPECT_TRUE(m.plan(AgentFrame{{&id, 1}, {&pos, 1}, {&vel, 1}, {&theta, 1}}, kDt,
                       FeedbackPolicy::kIgnored)
                    .ok());
    out.yaw.push_back(m.plans().lower_yaw[m.plans().slot_of_agent[0]]);
    pos += vel * kDt;
  }
  return out;
}

TEST(Mediator, LowerBodyTurnsSpeedUpAndSlowDown) {
  constexpr float kDt = 1.0f / 60.0f;
  auto rates = [&](const YawTrace& t) {
    std::vector<float> w;
    for (size_t f = 1; f < t.yaw.size(); ++f) w.push_back(wrap_pi(t.yaw[f] - t.yaw[f - 1]) / kDt);
    return w;
  };
  auto largest_rate_change = [&](const std::vector<float>& w) {
    float most = 0.0f;
    for (size_t f = 1; f < w.size(); ++f) most = std::max(most, std::abs(w[f] - w[f - 1]));
    return most;
  };
  MediatorParams p;
  const float accel = glm::radians(p.lower_turn_accel_deg_s2);
  const float rate = glm::radians(p.lower_turn_rate_deg_s);
  // 60 degrees one way, then back, every 12 frames (0.2 s).
  const std::vector<float> w = rates(zig_zag(p, 240, 12, 60.0f));
  EXPECT_LE(largest_rate_change(w), accel * kDt * 1.001f + 1e-4f);
  float fastest = 0.0f;
  for (float x : w) fastest = std::max(fastest, std::abs(x));
  EXPECT_LE(fastest, rate * 1.001f);
  EXPECT_GE(fastest, 0.5f * rate) << "it still turns";
  // Without the limit the same zig-zag reverses the turn within a frame.
  MediatorParams unlimited = p;
  unlimited.lower_turn_accel_deg_s2 = 1e6f;
  EXPECT_GE(largest_rate_change(rates(zig_zag(unlimited, 240, 12, 60.0f))), 1.5f * rate);
  // One 90 degree turn: reached, and passed no further than the target itself goes (the root's
  // heading, with the stride's own sway, swings a few degrees past and back; the unlimited turn
  // follows it exactly): the limit adds no overshoot of its own.
  const YawTrace turn = zig_zag(p, 120, 60, 90.0f);
  const YawTrace target = zig_zag(unlimited, 120, 60, 90.0f);
  EXPECT_LE(*std::max_element(turn.yaw.begin(), turn.yaw.end()),
            *std::max_element(target.yaw.begin(), target.yaw.end()) + glm::radians(0.1f));
  EXPECT_NEAR(turn.yaw.back(), glm::radians(90.0f), glm::radians(1.0f));
}

// turn_toward alone: a turn whose target is not a number turns nothing and keeps its state
// usable; from rest, a quarter turn is reached exactly and at rest.
TEST(Springs, TurnTowardKeepsItsStateAndLandsAtRest) {
  float angle = 0.25f, rate = 2.0f;
  turn_toward(angle, rate, std::numeric_limits<float>::quiet_NaN(), 5.0f, 100.0f, 1.0f / 60.0f);
  EXPECT_TRUE(std::isfinite(angle) && std::isfinite(rate));
  angle = rate = 0.0f;
  const float target = 0.5f * std::numbers::pi_v<float>;
  for (int f = 0; f < 600 && !(angle == target && rate == 0.0f); ++f) {
    const float before = angle;
    turn_toward(angle, rate, target, 5.0f, 100.0f, 1.0f / 60.0f);
    EXPECT_LE(angle, target) << f;
    EXPECT_GE(angle, before) << f;
  }
  EXPECT_EQ(angle, target);
  EXPECT_EQ(rate, 0.0f);
}

TEST(Mediator, TurnFeedbackLeavesLibrariesWithDirectionClipsAlone) {
  // Forward and backward clips, walking straight while looking 100 degrees aside: the legs switch
  // to the backward clips, and the simulator must not be pulled along with them.
  const LocomotionLibrary lib = test::builtin_library_without({"strafe"});
  ASSERT_TRUE(lib.has_direction_clips());
  const TurningRun r = run_turn(lib, MediatorParams{}, 0.0f, 100.0f);
  EXPECT_EQ(r.feedback_frames, 0);
  EXPECT_NEAR(r.position.x, 0.0f, 0.01f);
}

// A simulator that asks a standing agent for walking speed at once (social forces and Detour both
// can: their acceleration is a force, not a gait) is held to the speed-up legs deliver: the agent
// starts over about a second (1.5 m/s at max_accel_m_s2 = 1.5), never in a frame, and gets there.
// Returns the frames from the request until the fed-back speed reached 99% of it.
int frames_to_start(const MediatorParams& p, float want_m_s) {
  const LocomotionLibrary& lib = builtin_library();
  Mediator m(lib, p, 1);
  const uint32_t id = 1;
  glm::vec2 pos(0.0f), vel(0.0f);
  const float theta = 0.0f;
  constexpr float kDt = 1.0f / 60.0f;
  float last = 0.0f;
  for (int f = 0; f < 300; ++f) {
    if (f >= 30) vel = glm::vec2(0.0f, want_m_s);  // the simulator's wish, every frame
    EXPECT_TRUE(m.plan(AgentFrame{{&id, 1}, {&pos, 1}, {&vel, 1}, {&theta, 1}}, kDt,
                       FeedbackPolicy::kHonoured)
                    .ok());
    // The source honours it: the velocity it moves with is the one fed back.
    const glm::vec2 fed = m.feedback().velocities[0];
    const float speed = glm::length(fed);
    // Never more than one frame of the limit above what the body had (which lags behind it).
    EXPECT_LE(speed, last + p.max_accel_m_s2 * kDt + 1e-4f) << f;
    last = std::max(last, speed);
    if (f >= 30 && speed >= 0.99f * want_m_s) return f - 30;
    vel = fed;
    pos += vel * kDt;
  }
  return -1;
}

TEST(Mediator, FeedsBackAStartTheLegsCanMake) {
  MediatorParams p;
  const int frames = frames_to_start(p, 1.5f);
  ASSERT_GE(frames, 0) << "the agent never got to its speed";
  // 99% of 1.5 m/s at 1.5 m/s^2: 0.99 s at the very least (59 frames).
  EXPECT_GE(frames, static_cast<int>(0.99f * 1.5f / p.max_accel_m_s2 * 60.0f));
  EXPECT_LE(frames, 120);
  // A limit as high as the simulator's own: the start is the simulator's, within a few frames.
  p.max_accel_m_s2 = 20.0f;
  const int fast = frames_to_start(p, 1.5f);
  ASSERT_GE(fast, 0);
  EXPECT_LT(fast, 30);
}

TEST(Mediator, AsksNoFeedbackOfASourceThatIgnoresIt) {
  // 9 m/s is beyond the clips: an honouring source is told the speed, a replay nothing.
  const LocomotionLibrary& lib = builtin_library();
  for (FeedbackPolicy policy : {FeedbackPolicy::kHonoured, FeedbackPolicy::kIgnored}) {
    Mediator m(lib, MediatorParams{}, 1);
    const uint32_t id = 1;
    const glm::vec2 pos(0.0f), vel(0.0f, 9.0f);
    const float theta = 0.0f;
    ASSERT_TRUE(
        m.plan(AgentFrame{{&id, 1}, {&pos, 1}, {&vel, 1}, {&theta, 1}}, 1.0f / 60.0f, policy).ok());
    EXPECT_EQ(m.feedback().has_feedback[0], policy == FeedbackPolicy::kHonoured ? 1 : 0);
    if (policy == FeedbackPolicy::kIgnored) {
      EXPECT_EQ(m.feedback().velocities[0], vel);
    }
  }
}

TEST(Mediator, SurvivesNaNAndAbsurdInput) {
  std::vector<Script> s{
      {{0, 0},
       [](double t) { return t > 1.0 && t < 2.0 ? glm::vec2(NAN, 1.0f) : glm::vec2(0, 1.2f); },
       nullptr},
      {{3, 0},
       [](double t) { return t > 1.0 && t < 1.5 ? glm::vec2(0, 1e6f) : glm::vec2(0, 1.2f); },
       nullptr},
      {{6, 0},
       [](double) { return glm::vec2(0, 1.2f); },
       [](double, glm::vec2) { return float(NAN); }}};
  const auto r = run_scripted(builtin_library(), s, MediatorParams{}, 240);
  EXPECT_GT(r.sanitised, 0u);
  EXPECT_TRUE(std::isfinite(r.report.root_error_cm.max));
  EXPECT_TRUE(std::isfinite(r.report.slide.mean_cm_s));
}

TEST(Mediator, ZeroAgentsAndCapacity) {
  const LocomotionLibrary& lib = builtin_library();
  Mediator m(lib, MediatorParams{}, 2);
  EXPECT_TRUE(m.plan(AgentFrame{}, 1.0f / 60.0f).ok());
  const uint32_t ids[3] = {1, 2, 3};
  const glm::vec2 p[3] = {}, v[3] = {};
  const float th[3] = {};
  const Status s = m.plan(AgentFrame{ids, p, v, th}, 1.0f / 60.0f);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("capacity"), std::string::npos) << s.message();
  EXPECT_FALSE(m.plan(AgentFrame{}, 0.0f).ok());
}

TEST(Mediator, AgentsComeAndGo) {
  const LocomotionLibrary& lib = builtin_library();
  Mediator m(lib, MediatorParams{}, 4);
  PoseSynthesizer ps(lib, 4, true);
  const glm::vec2 p[4] = {{0, 0}, {1, 0}, {2, 0}, {3, 0}};
  const glm::vec2 v[4] = {{0, 1}, {0, 1}, {0, 1}, {0, 1}};
  const float th[4] = {};
  // Ids 10..13, then 12..15: two vanish, two appear; slots must be reused, never exceeded.
  for (int round = 0; round < 50; ++round) {
    const uint32_t base = 10 + 2 * (round % 5);
    const uint32_t ids[4] = {base, base + 1, base + 2, base + 3};
    ASSERT_TRUE(m.plan(AgentFrame{ids, p, v, th}, 1.0f / 60.0f).ok());
    ps.run(m.plans(), m.num_agents(), m.params(), 1.0f / 60.0f);
    for (int i = 0; i < 4; ++i) {
      const int slot = m.plans().slot_of_agent[i];
      ASSERT_GE(slot, 0);
      ASSERT_LT(slot, 4);
      const glm::vec3 root = translation_of(ps.world(slot)[lib.skeleton->role(JointRole::kHips)]);
      EXPECT_NEAR(root.x, p[i].x, 0.1f);
    }
  }
}

// Pose synthesis poses some joints twice and some once (the spine twist's range after the twist,
// the feet after leg IK): whatever the path, every joint's world transform must be its parent's
// times its final local rotation, or a joint was left behind from an earlier pass or frame.
TEST(Mediator, WorldJointsFollowTheirFinalLocalRotations) {
  const LocomotionLibrary& lib = builtin_library();
  const Skeleton& sk = *lib.skeleton;
  Mediator m(lib, MediatorParams{}, 4);
  PoseSynthesizer ps(lib, 4, true);
  const uint32_t ids[4] = {1, 2, 3, 4};
  const glm::vec2 v[4] = {{0, 0.6f}, {0, 1.3f}, {0.4f, 2.6f}, {0, 0}};
  const float th[4] = {0.9f, -0.7f, 0.3f, 1.2f};  // looking aside: the spine twists
  glm::vec2 p[4] = {{0, 0}, {2, 0}, {4, 0}, {6, 0}};
  constexpr float kDt = 1.0f / 60.0f;
  for (int f = 0; f < 90; ++f) {
    for (int i = 0; i < 4; ++i) p[i] += v[i] * kDt;
    ASSERT_TRUE(m.plan(AgentFrame{ids, p, v, th}, kDt).ok());
    ps.run(m.plans(), m.num_agents(), m.params(), kDt);
    for (int i = 0; i < 4; ++i) {
      const int slot = m.plans().slot_of_agent[i];
      const std::span<const glm::mat4> w = ps.world(slot);
      const std::span<const glm::quat> local = ps.local_rotations(slot);
      for (int j = 0; j < sk.num_joints(); ++j) {
        const int parent = sk.parents[j];
        if (parent < 0) continue;
        const glm::quat rel = glm::quat_cast(glm::mat3(glm::inverse(w[parent]) * w[j]));
        ASSERT_GT(std::abs(glm::dot(glm::normalize(rel), local[j])), 1.0f - 1e-5f)
            << "frame " << f << ", agent " << i << ", joint " << sk.names[j];
      }
    }
  }
  EXPECT_GT(std::abs(ps.torsion(m.plans().slot_of_agent[0])), 0.1f);  // the twist path ran
}

// Issue #11: plan() checks the whole frame before it writes anything. Before, a repeated newcomer
// id was found after num_agents_, slot_of_agent and the id map (vanished agents erased) had been
// written: the app then drew half-written plans, and the next good frame restarted agents.
TEST(Mediator, RefusedFrameChangesNothing) {
  const LocomotionLibrary& lib = builtin_library();
  Mediator m(lib, MediatorParams{}, 6);
  const glm::vec2 p[5] = {{0, 0}, {1, 0}, {2, 0}, {3, 0}, {4, 0}};
  const glm::vec2 v[5] = {{0, 1}, {0, 1.2f}, {0, 1.4f}, {0, 1}, {0, 1}};
  const float th[5] = {};
  const uint32_t good[3] = {1, 2, 3};
  for (int f = 0; f < 30; ++f) {
    ASSERT_TRUE(m.plan(AgentFrame{{good, 3}, {p, 3}, {v, 3}, {th, 3}}, 1.0f / 60.0f).ok());
  }
  const AnimationPlans before = m.plans();
  const FeedbackBuffers feedback_before = m.feedback();
  auto expect_unchanged = [&](const char* what) {
    SCOPED_TRACE(what);
    EXPECT_EQ(m.num_agents(), 3u);
    const AnimationPlans& now = m.plans();
    EXPECT_EQ(now.slot_of_agent, before.slot_of_agent);
    EXPECT_EQ(now.agent_of_slot, before.agent_of_slot);
    EXPECT_EQ(now.layer_clip, before.layer_clip);
    EXPECT_EQ(now.layer_weight, before.layer_weight);
    EXPECT_EQ(now.layer_time_s, before.layer_time_s);
    EXPECT_EQ(now.root_xz, before.root_xz);
    EXPECT_EQ(now.lower_yaw, before.lower_yaw);
    EXPECT_EQ(now.phase, before.phase);
    EXPECT_EQ(now.fresh, before.fresh);
    EXPECT_EQ(m.feedback().velocities, feedback_before.velocities);
    EXPECT_EQ(m.feedback().has_feedback, feedback_before.has_feedback);
  };
  // Agent 3 vanishes, and newcomer 9 comes twice.
  const uint32_t twice_new[4] = {1, 2, 9, 9};
  Status s = m.plan(AgentFrame{{twice_new, 4}, {p, 4}, {v, 4}, {th, 4}}, 1.0f / 60.0f);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("agent id 9 appears twice"), std::string::npos) << s.message();
  expect_unchanged("newcomer twice");
  const uint32_t twice_known[4] = {1, 2, 3, 2};
  s = m.plan(AgentFrame{{twice_known, 4}, {p, 4}, {v, 4}, {th, 4}}, 1.0f / 60.0f);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("agent id 2 appears twice"), std::string::npos) << s.message();
  expect_unchanged("known agent twice");
  const uint32_t reserved[4] = {1, 5, 0xffffffffu, 2};
  EXPECT_FALSE(m.plan(AgentFrame{{reserved, 4}, {p, 4}, {v, 4}, {th, 4}}, 1.0f / 60.0f).ok());
  expect_unchanged("reserved id");
  s = m.plan(AgentFrame{{good, 3}, {p, 2}, {v, 3}, {th, 3}}, 1.0f / 60.0f);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("differ in length"), std::string::npos) << s.message();
  expect_unchanged("short positions");
  EXPECT_FALSE(m.plan(AgentFrame{{good, 3}, {p, 3}, {v, 3}, {th, 3}}, NAN).ok());
  expect_unchanged("NaN frame time");

  // The scratch of the refused frames left nothing behind: the same agents carry on in their
  // slots (none restarted), and the newcomer 9 of the refused frame is new when it really comes.
  ASSERT_TRUE(m.plan(AgentFrame{{good, 3}, {p, 3}, {v, 3}, {th, 3}}, 1.0f / 60.0f).ok());
  EXPECT_EQ(m.plans().slot_of_agent, before.slot_of_agent);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(m.plans().fresh[m.plans().slot_of_agent[i]], 0) << i;
  const uint32_t with_9[4] = {1, 2, 3, 9};
  ASSERT_TRUE(m.plan(AgentFrame{{with_9, 4}, {p, 4}, {v, 4}, {th, 4}}, 1.0f / 60.0f).ok());
  EXPECT_EQ(m.plans().fresh[m.plans().slot_of_agent[3]], 1);
}

// Issue #12: a parameter file must fail with a message, whatever is wrong with it.
TEST(MediatorParams, JsonNumberTooLargeNamesFileAndLine) {
  const std::string path = test::scratch_dir("params") + "/huge.json";
  std::ofstream(path) << "{\n  \"torsion_limit_deg\": 1e400\n}\n";
  MediatorParams p;
  const Status s = load_mediator_params_json(path, &p);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message().rfind(path + ": invalid JSON: number too large at line 2", 0), 0u)
      << s.message();
  EXPECT_NE(s.message().find("'1e400'"), std::string::npos) << s.message();
  EXPECT_EQ(p.torsion_limit_deg, MediatorParams{}.torsion_limit_deg);
}

TEST(MediatorParams, JsonTextInMemorySetsAndNamesTheSource) {
  MediatorParams p;
  ASSERT_TRUE(
      parse_mediator_params_json(R"({"torsion_limit_deg": 40, "foot_locking": false})", "mem", &p)
          .ok());
  EXPECT_EQ(p.torsion_limit_deg, 40.0f);
  EXPECT_FALSE(p.foot_locking);
  const Status s = parse_mediator_params_json(R"({"torsion_limit_deg": 400})", "mem.json", &p);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message().rfind("mem.json: torsion_limit_deg", 0), 0u) << s.message();
  EXPECT_FALSE(parse_mediator_params_json("[1, 2]", "mem.json", &p).ok());
}

TEST(MediatorParams, DirectoryIsNotAParameterFile) {
  const std::string dir = test::scratch_dir("params") + "/folder.json";
  std::filesystem::create_directories(dir);
  MediatorParams p;
  const Status s = load_mediator_params_json(dir, &p);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message(), dir + ": is a directory, expected a parameter file");
  const Status missing = load_mediator_params_json(dir + "/none.json", &p);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.message().find("none.json: cannot open the parameter file"), std::string::npos)
      << missing.message();
}

}  // namespace
}  // namespace gk
