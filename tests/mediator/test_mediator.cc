// The mediator on scripted crowds with the built-in clips: planted feet, rate limits, torsion
// limit, facing, feedback and robustness, each measured with the METRICS.md definitions.

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "animation/pose_jobs.h"
#include "mediator/springs.h"
#include "tests/mediator/mediator_fixture.h"

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

TEST(Mediator, FeedsBackTheSpeedItCanDeliver) {
  // 9 m/s is beyond anything the clips can do (3.6 x 1.35 x 1.2 = 5.83 m/s).
  std::vector<Script> s{straight({0, 0}, {0.0f, 9.0f})};
  const auto r = run_scripted(builtin_library(), s, MediatorParams{}, 120);
  ASSERT_TRUE(r.report.feedback_speed_change.has_value());
  EXPECT_NEAR(*r.report.feedback_speed_change, 1.0 - 3.6 * 1.35 * 1.2 / 9.0, 0.01);
  EXPECT_EQ(r.feedback_frames, 120);
}

TEST(Mediator, FeedsBackAWalkingDirectionTheLegsCanTake) {
  // Walking +z at 1.3 m/s, the simulator turns the velocity to +x in one frame (a jam's jitter).
  // The legs turn at lower_turn_rate_deg_s, so the velocity fed back stays within
  // turn_feedback_deg of where they walk, and reaches +x once they have turned.
  const LocomotionLibrary& lib = builtin_library();
  MediatorParams p;
  Mediator m(lib, p, 1);
  const float dt = 1.0f / 60.0f;
  const uint32_t id = 5;
  glm::vec2 pos(0.0f), vel(0.0f, 1.3f);
  float theta = 0.0f;
  int turned_back = 0;
  float last_dir = 0.0f;
  for (int f = 0; f < 120; ++f) {
    if (f == 60) vel = glm::vec2(1.3f, 0.0f);
    theta = std::atan2(vel.x, vel.y);
    ASSERT_TRUE(m.plan(AgentFrame{{&id, 1}, {&pos, 1}, {&vel, 1}, {&theta, 1}}, dt).ok());
    const FeedbackBuffers& fb = m.feedback();
    const glm::vec2 out = fb.velocities[0];
    const float dir = std::atan2(out.x, out.y);
    const float walked = m.plans().travel_yaw[m.plans().slot_of_agent[0]];
    EXPECT_LE(std::abs(wrap_pi(dir - walked)), glm::radians(p.turn_feedback_deg) + 1e-3f) << f;
    EXPECT_NEAR(glm::length(out), 1.3f, 1e-3f) << f;  // the speed is kept
    if (fb.has_feedback[0]) ++turned_back;
    pos += out * dt;  // an honouring simulator moves with the velocity fed back, and asks again
    last_dir = dir;
  }
  EXPECT_GE(turned_back, 3);  // a 90 degree turn at 300 deg/s takes 0.3 s
  EXPECT_LE(turned_back, 40);
  EXPECT_NEAR(last_dir, std::numbers::pi_v<float> / 2.0f, glm::radians(p.turn_feedback_deg));
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
    ps.run(m, 1.0f / 60.0f);
    for (int i = 0; i < 4; ++i) {
      const int slot = m.plans().slot_of_agent[i];
      ASSERT_GE(slot, 0);
      ASSERT_LT(slot, 4);
      const glm::vec3 root = translation_of(ps.world(slot)[lib.skeleton->role(JointRole::kHips)]);
      EXPECT_NEAR(root.x, p[i].x, 0.1f);
    }
  }
}

}  // namespace
}  // namespace gk
