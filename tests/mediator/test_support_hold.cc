// A foot that carries the body alone holds it back (issue #9: in a Detour jam the simulator's
// velocity lurches faster than legs can follow, and the support foot was dragged along or let go
// while the other was in the air). The root pass brakes the root as the support leg straightens
// (no harder than kSupportBrake: a root that cannot stop in time leaves the reach, and the foot
// gives), keeps its direction, and the feedback gives the simulator the held position and the
// speed kept.

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "mediator/mediator_passes.h"
#include "tests/mediator/mediator_fixture.h"
#include "tests/mediator/scripted_crowd.h"

namespace gk {
namespace {

constexpr float kDt = 1.0f / 60.0f;

// One agent in slot 0, walking along +z, its support foot's reach a circle about `centre`.
struct OneAgent {
  const LocomotionLibrary& lib = test::builtin_library();
  MediatorParams params = [] {
    MediatorParams p;
    p.support_hold = true;  // off by default
    return p;
  }();
  std::vector<int32_t> slot_of_agent{0};
  std::vector<uint8_t> fresh{0};
  std::vector<glm::vec2> positions{glm::vec2(0.0f, 1.0f)};
  std::vector<glm::vec2> vel{glm::vec2(0.0f, 1.2f)};
  std::vector<uint8_t> standing{0};
  std::vector<float> lower_yaw{0.0f};
  std::vector<glm::vec2> root_xz{glm::vec2(0.0f, 0.98f)};
  std::vector<float> root_heading{0.0f};
  // The leg lets the root go 0.49 m from (0, 0.5); no landing of the other foot in sight.
  std::vector<SupportReach> reach{SupportReach{glm::vec2(0.0f, 0.5f), 0.49f, -1.0f}};
  std::vector<glm::vec2> hold{glm::vec2(0.0f)};
  std::vector<float> hold_scale{1.0f};
  std::vector<float> root_speed{1.2f};

  // One root pass; returns the root it drew.
  glm::vec2 root_step(bool honoured, bool with_reach = true) {
    const PassCrowd crowd{lib, params, kDt, slot_of_agent, fresh};
    root_pass(crowd, positions, vel, standing, lower_yaw, root_xz, root_heading,
              with_reach ? std::span<const SupportReach>(reach) : std::span<const SupportReach>(),
              honoured, root_speed, hold, hold_scale);
    return root_xz[0];
  }
};

glm::vec2 unheld_root(const OneAgent& a) {
  return pulled_root(a.root_xz[0], a.vel[0], a.positions[0], kDt, root_pull(kDt));
}

TEST(SupportHold, TheRootSlowsWithinTheReachAndKeepsItsDirection) {
  OneAgent a;
  a.reach[0].radius = 0.53f;  // 5 cm left: less than braking at kSupportBrake from 1.2 m/s takes
  a.vel[0] = glm::vec2(0.6f, 1.04f);  // 1.2 m/s, 30 deg off the line from the foot
  a.positions[0] = glm::vec2(0.01f, 1.0f);
  const glm::vec2 prev = a.root_xz[0];
  const glm::vec2 free_root = unheld_root(a);
  const glm::vec2 centre = a.reach[0].centre;
  // Free, the root would come closer to the edge than it can still stop in.
  ASSERT_GT(glm::length(free_root - centre), 0.49f);
  const float speed_before = a.root_speed[0];
  const glm::vec2 root = a.root_step(/*honoured=*/true);
  EXPECT_LE(glm::length(root - centre), a.reach[0].radius);
  const glm::vec2 step = root - prev, free_step = free_root - prev;
  EXPECT_GT(glm::dot(step, glm::normalize(free_step)), 0.0f);  // slowed, not stopped
  EXPECT_LT(glm::length(step), glm::length(free_step));
  // Braked no harder than kSupportBrake from last frame's speed.
  EXPECT_GE(glm::length(step) / kDt, speed_before - kSupportBrake * kDt - 1e-3f);
  // The same direction: the lower body's travel (and the heading metric) does not swing.
  EXPECT_NEAR(step.x * free_step.y - step.y * free_step.x, 0.0f, 1e-7f);
  // The hold is what the root was held back by, and the simulator is given it.
  EXPECT_NEAR(glm::length(a.hold[0] - (root - free_root)), 0.0f, 1e-6f);
  std::vector<uint8_t> has(1, 0);
  std::vector<glm::vec2> fb_p(1), fb_v(1);
  std::vector<float> fb_theta(1), fed_speed{1.2f}, gait_weight{1.0f}, thetas{0.0f};
  const PassCrowd crowd{a.lib, a.params, kDt, a.slot_of_agent, a.fresh};
  feedback_pass(crowd, true, a.positions, a.vel, thetas, fed_speed, a.lower_yaw, a.standing,
                gait_weight, a.hold, a.hold_scale, {has, fb_p, fb_v, fb_theta});
  EXPECT_EQ(has[0], 1);
  EXPECT_NEAR(glm::length(fb_p[0] - (a.positions[0] + a.hold[0])), 0.0f, 1e-6f);
  // With the speed the body kept: the share of its step, along the same direction.
  const float kept = glm::length(step) / glm::length(free_step);
  EXPECT_NEAR(glm::length(fb_v[0] - a.vel[0] * kept), 0.0f, 1e-5f);
}

// Pushed on frame after frame, the body comes to rest at the edge of the leg's reach with its
// speed falling every frame, never faster than kSupportBrake (no jolt), and the simulator's agent
// stays with the drawn root.
TEST(SupportHold, APushedBodyComesToRestAtTheEdgeOfTheReach) {
  OneAgent a;
  a.root_xz[0] = glm::vec2(0.0f, 0.80f);  // 19 cm from the edge, walking at 1.2 m/s
  a.positions[0] = glm::vec2(0.0f, 0.80f);
  const glm::vec2 centre = a.reach[0].centre;
  float last_speed = 1e9f;
  int held = 0;
  for (int f = 0; f < 45; ++f) {
    const glm::vec2 prev = a.root_xz[0];
    const glm::vec2 root = a.root_step(true);
    const float speed = glm::length(root - prev) / kDt;
    EXPECT_LE(glm::length(root - centre), a.reach[0].radius + 1e-4f) << f;
    if (a.hold[0] != glm::vec2(0.0f)) {  // from the first hold on
      EXPECT_LE(speed, last_speed + 1e-4f) << f;
      if (last_speed < 1e8f) {
        EXPECT_LE((last_speed - speed) / kDt, kSupportBrake * 1.01f) << f;
      }
      last_speed = speed;
      ++held;
    }
    a.positions[0] += a.hold[0];  // the simulator takes the held position
    EXPECT_LE(glm::length(root - a.positions[0]), kMaxRootOffset + 1e-6f) << f;
    a.positions[0] += a.vel[0] * kDt;  // and pushes on
  }
  EXPECT_LT(a.reach[0].radius - glm::length(a.root_xz[0] - centre), 1e-3f);
  EXPECT_GT(held, 20);
  EXPECT_LT(last_speed, 0.05f);
}

TEST(SupportHold, NothingIsHeldWithoutFeedbackOrWhenOff) {
  {
    OneAgent a;  // a source that ignores feedback (a replay): the root would only lag p
    const glm::vec2 free_root = unheld_root(a);
    EXPECT_EQ(a.root_step(/*honoured=*/false), free_root);
    EXPECT_EQ(a.hold[0], glm::vec2(0.0f));
  }
  {
    OneAgent a;
    a.params.support_hold = false;
    const glm::vec2 free_root = unheld_root(a);
    EXPECT_EQ(a.root_step(true), free_root);
    EXPECT_EQ(a.hold[0], glm::vec2(0.0f));
  }
  {
    OneAgent a;  // no foot carries the body alone
    a.reach[0].radius = -1.0f;
    EXPECT_EQ(a.root_step(true), unheld_root(OneAgent{}));
  }
  {
    OneAgent a;  // no reach given (a mediator without pose synthesis)
    const glm::vec2 free_root = unheld_root(a);
    EXPECT_EQ(a.root_step(true, /*with_reach=*/false), free_root);
  }
  {
    OneAgent a;  // moving toward the foot is never held
    a.vel[0] = glm::vec2(0.0f, -1.2f);
    a.positions[0] = glm::vec2(0.0f, 0.96f);
    const glm::vec2 free_root = unheld_root(a);
    EXPECT_EQ(a.root_step(true), free_root);
  }
}

// The other foot comes down in time: the root walks on unheld (a steady walk's late stance).
// Not in time: it covers what is left of the reach by the landing, at an even speed.
TEST(SupportHold, TheRootMayUseTheReachUntilTheOtherFootLands) {
  {
    OneAgent a;
    a.reach[0].radius = 0.60f;     // 12 cm left
    a.reach[0].landing_s = 0.05f;  // 3 frames: 6 cm at 1.2 m/s
    const glm::vec2 free_root = unheld_root(a);
    EXPECT_EQ(a.root_step(true), free_root);
    EXPECT_EQ(a.hold[0], glm::vec2(0.0f));
  }
  {
    OneAgent a;  // at 0.6 m/s
    a.vel[0] = glm::vec2(0.0f, 0.6f);
    a.root_speed[0] = 0.6f;
    a.positions[0] = glm::vec2(0.0f, 0.99f);
    a.reach[0].radius = 0.52f;            // 4 cm left
    a.reach[0].landing_s = 0.1f + 1e-3f;  // 6 frames: 6 cm at 0.6 m/s
    const glm::vec2 centre = a.reach[0].centre;
    float speed[6];
    for (int f = 0; f < 6; ++f) {
      const glm::vec2 prev = a.root_xz[0];
      a.root_step(true);
      speed[f] = glm::length(a.root_xz[0] - prev) / kDt;
      a.positions[0] += a.hold[0] + a.vel[0] * kDt;
      a.reach[0].landing_s -= kDt;
    }
    // 4 cm in 0.1 s: about 0.4 m/s to the landing, after a brake no harder than kSupportBrake.
    EXPECT_LE(glm::length(a.root_xz[0] - centre), a.reach[0].radius + 1e-4f);
    EXPECT_GT(glm::length(a.root_xz[0] - centre), a.reach[0].radius - 5e-3f);
    EXPECT_GE(speed[0], 0.6f - kSupportBrake * kDt - 1e-3f);
    EXPECT_NEAR(speed[5], 0.04f / 0.1f, 0.1f);
  }
}

// A root already beyond the reach (the foot was pinned behind a lurch) goes no further from the
// foot if it has come to rest, and is not pulled back toward it either: it waits for the other
// foot. One still moving is not stopped dead: it brakes at kSupportBrake, and the foot gives.
TEST(SupportHold, ARootBeyondTheReachNeverMovesBackwardNorStopsDead) {
  {
    OneAgent a;
    a.root_xz[0] = glm::vec2(0.0f, 1.03f);
    a.positions[0] = glm::vec2(0.0f, 1.05f);
    a.root_speed[0] = 0.0f;
    const glm::vec2 prev = a.root_xz[0];
    const glm::vec2 root = a.root_step(true);
    EXPECT_NEAR(glm::length(root - prev), 0.0f, 1e-6f);
  }
  {
    OneAgent a;
    a.root_xz[0] = glm::vec2(0.0f, 1.03f);
    a.positions[0] = glm::vec2(0.0f, 1.05f);
    const glm::vec2 prev = a.root_xz[0];
    const glm::vec2 free_root = unheld_root(a);
    const glm::vec2 root = a.root_step(true);
    EXPECT_NEAR(glm::length(root - prev) / kDt, 1.2f - kSupportBrake * kDt, 1e-3f);
    EXPECT_LT(glm::length(root - prev), glm::length(free_root - prev));
  }
}

// Through the pipeline: pose synthesis publishes a reach exactly for the agents with one foot
// pinned and the other not, about the pinned foot, no larger than the leg; the landing of the
// other foot is expected within a stride.
TEST(SupportHold, PoseSynthesisPublishesTheReachOfASingleSupportFoot) {
  const LocomotionLibrary& lib = test::builtin_library();
  std::vector<test::Script> scripts;
  for (int i = 0; i < 4; ++i) {
    scripts.push_back(test::straight(glm::vec2(2.0f * i, 0.0f), glm::vec2(0.3f, 1.1f + 0.2f * i)));
  }
  test::ScriptedCrowd crowd(scripts, /*honour_feedback=*/true);
  MediatorParams params;
  params.support_hold = true;
  CrowdPipeline pipeline(lib, params, test::test_pipeline_options(crowd.capacity(), kDt));
  int published = 0, single = 0, late = 0;
  const float leg = std::max(lib.leg_length_m[0], lib.leg_length_m[1]);
  for (int f = 0; f < 240; ++f) {
    ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
    const AnimationPlans& pl = pipeline.mediator().plans();
    const std::span<const SupportReach> reach = pipeline.poses().support_reach();
    const FootLocks& locks = pipeline.poses().foot_locks();
    for (size_t i = 0; i < crowd.capacity(); ++i) {
      const int slot = pl.slot_of_agent[i];
      const bool l = locks.lock[slot * 2].state == FootLockState::kLocked;
      const bool r = locks.lock[slot * 2 + 1].state == FootLockState::kLocked;
      if (f > 0 && l != r) ++single;
      const SupportReach& sr = reach[slot];
      if (sr.radius < 0.0f) continue;
      ++published;
      EXPECT_NE(l, r) << "frame " << f << " agent " << i;
      EXPECT_LE(sr.radius, leg) << f;
      // The circle is about the pinned foot, placed for the root: its centre is where the root
      // stands over that foot, within a leg's length of the root.
      EXPECT_LT(glm::length(sr.centre - pl.root_xz[slot]), leg) << f;
      if (sr.landing_s >= 1.0f) ++late;  // a walk's swing lasts about 0.4 s
    }
  }
  EXPECT_GT(published, 100);
  // From the other foot's swing progress over the last frame: as good as that rate (a swing that
  // slows, as a start's first step does, is expected to land late).
  EXPECT_LT(late, published / 50);

  EXPECT_GT(published, single / 2);

  // Off (the default), the reach is published all the same: the rate pass quickens the steps by
  // it (ReachBoost below), though the root pass holds nothing.
  test::ScriptedCrowd plain(scripts, /*honour_feedback=*/true);
  CrowdPipeline off(lib, MediatorParams{}, test::test_pipeline_options(plain.capacity(), kDt));
  int published_off = 0;
  for (int f = 0; f < 240; ++f) {
    ASSERT_TRUE(off.step(plain, kDt).ok());
    for (size_t i = 0; i < plain.capacity(); ++i) {
      if (off.poses().support_reach()[off.mediator().plans().slot_of_agent[i]].radius >= 0.0f) {
        ++published_off;
      }
    }
  }
  EXPECT_GT(published_off, 100);
}

// The rate pass alone: one agent walking the built-in walk at its own speed (rate 1), its support
// foot's reach about to be left. Quicker steps are asked for exactly while the body would leave
// the reach before the other foot lands, eased in and out over kReachBoostTime, never beyond the
// rate limit; not for a re-planting step, whose landing the gait's rate does not bring sooner.
struct RatePass {
  const LocomotionLibrary& lib = test::builtin_library();
  MediatorParams params;
  std::vector<int32_t> slot_of_agent{0};
  std::vector<uint8_t> fresh{0};
  std::vector<int16_t> layer_clip = std::vector<int16_t>(kMaxBlendLayers, 0);
  std::vector<float> layer_weight = std::vector<float>(kMaxBlendLayers, 0.0f);
  std::vector<float> speed, cadence{1.0f}, lower_yaw{0.0f}, transition_weight{0.0f};
  std::vector<float> phase{0.0f}, idle{0.0f}, rate{1.0f}, gait{1.0f}, travel{0.0f};
  std::vector<glm::vec2> root_xz{glm::vec2(0.0f, 0.98f)}, vel{glm::vec2(0.0f, 1.2f)};
  // The root is 0.48 m from the foot's centre, 0.01 m inside its reach, moving straight away.
  std::vector<SupportReach> reach{SupportReach{glm::vec2(0.0f, 0.5f), 0.49f, 0.3f}};
  std::vector<float> boost{1.0f};
  RatePass() {
    const DirectionGroup& g = lib.groups[lib.forward_group];
    layer_clip[0] = static_cast<int16_t>(g.clips.front());  // the slowest forward walk
    layer_weight[0] = 1.0f;
    speed = {lib.clips[g.clips.front()].speed_m_s};
  }
  float step() {
    const PassCrowd crowd{lib, params, kDt, slot_of_agent, fresh};
    rate_phase_pass(crowd, layer_clip, layer_weight, speed, cadence, lower_yaw, transition_weight,
                    {reach, root_xz, vel, boost}, phase, idle, rate, gait, travel);
    return rate[0];
  }
};

TEST(ReachBoost, StepsQuickenWhileTheBodyWouldLeaveTheReachBeforeTheLanding) {
  RatePass a;
  const float first = a.step();
  // Eased in: from 1 toward the fastest rate by a frame's share of kReachBoostTime, not at once.
  EXPECT_NEAR(first, 1.0f + (a.params.max_playback_rate - 1.0f) * kDt / kReachBoostTime, 1e-4f);
  float r = first;
  for (int f = 0; f < 10; ++f) {
    const float next = a.step();
    EXPECT_GE(next, r - 1e-6f);
    r = next;
  }
  EXPECT_NEAR(r, a.params.max_playback_rate, 1e-4f);  // asked for 0.3 s / one frame: the limit
  // The other foot lands in time (the body 0.3 m inside the reach, 0.25 s at 1.2 m/s; the landing
  // 0.15 s away at the rate played, 0.2 s at the plain one): back to the plain rate, eased out.
  a.reach[0].radius = 0.78f;
  a.reach[0].landing_s = 0.15f;
  const float easing = a.step();
  EXPECT_LT(easing, r);
  EXPECT_GT(easing, 1.0f);
  for (int f = 0; f < 10; ++f) r = a.step();
  EXPECT_NEAR(r, 1.0f, 1e-4f);
}

TEST(ReachBoost, NotForAReplantingStepNorANewAgentNorATransition) {
  {
    RatePass a;
    a.reach[0].replanting = true;
    for (int f = 0; f < 5; ++f) EXPECT_NEAR(a.step(), 1.0f, 1e-4f);
  }
  {
    RatePass a;
    a.reach[0].radius = -1.0f;  // both feet pinned, or none
    for (int f = 0; f < 5; ++f) EXPECT_NEAR(a.step(), 1.0f, 1e-4f);
  }
  {
    RatePass a;
    a.vel[0] = glm::vec2(0.0f, -1.2f);  // walking back over the foot: no hurry
    for (int f = 0; f < 5; ++f) EXPECT_NEAR(a.step(), 1.0f, 1e-4f);
  }
  {
    RatePass a;
    a.fresh[0] = 1;  // a new agent: the slot's reach is its previous agent's
    for (int f = 0; f < 5; ++f) EXPECT_NEAR(a.step(), 1.0f, 1e-4f);
  }
  {
    RatePass a;
    a.transition_weight[0] = 0.5f;  // a start or stop plays: its own clock lands the feet
    for (int f = 0; f < 5; ++f) EXPECT_NEAR(a.step(), 1.0f, 1e-4f);
    EXPECT_EQ(a.boost[0], 1.0f);
  }
}

// Through the pipeline, with the mannequin's clips (a walk at 1.05 m/s, a jog at 2.6): pedestrians
// who set off briskly from a slow walk (0.3 -> 1.5 m/s in 0.7 s, as agents in a DetourCrowd
// plaza do). The slow blend's steps are short and its swing long, so the body outran the support
// foot before the other foot came down, and the stance leg was let go and re-pinned with both
// feet off the floor. Quicker steps while the body would leave the support's reach keep a foot
// down: float 0.0059 -> 0.0014, support slide 0.67 -> 0.38 cm/s; their support skate is higher
// (0.0004 -> 0.0018, landings at the quicker pace), within its bound.
TEST(ReachBoost, PedestriansSettingOffBrisklyKeepAFootDown) {
  GK_REQUIRE_DATA("clips/gltf/ual_mannequin_quaternius.glb");
  auto lib = test::load_data_library({"clips/gltf/ual_mannequin_quaternius.glb"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  auto run = [&](bool quicken) {
    std::vector<test::Script> scripts;
    for (int i = 0; i < 12; ++i) {
      const double t0 = 1.0 + 0.061 * i;  // setting off at every phase of the slow walk
      scripts.push_back({glm::vec2(1.5f * static_cast<float>(i), 0.0f), [t0](double t) {
                           const double u = std::clamp((t - t0) / 0.7, 0.0, 1.0);
                           return glm::vec2(
                               0.0f, static_cast<float>(0.3 + 1.2 * u * u * (3.0 - 2.0 * u)));
                         }});
    }
    test::ScriptedCrowd crowd(scripts);
    MediatorParams params;
    params.quicken_steps = quicken;
    CrowdPipeline pipeline(*lib, params, test::test_pipeline_options(crowd.capacity(), kDt));
    for (int f = 0; f < 240; ++f) EXPECT_TRUE(pipeline.step(crowd, kDt).ok());
    return pipeline.metrics()->finish();
  };
  const MetricsReport on = run(true), off = run(false);
  EXPECT_LT(2.0 * on.feet.float_ratio, off.feet.float_ratio);
  EXPECT_LT(on.feet.support_slide_cm_s, off.feet.support_slide_cm_s);
  EXPECT_LE(on.feet.float_ratio, 0.01);
  EXPECT_LE(on.feet.support_skate_ratio, 0.005);
  EXPECT_LE(on.feet.support_slide_cm_s, 2.0);
  EXPECT_LE(on.feet.limb_pop_rate, 1.0);
  EXPECT_EQ(on.playback_outside_limits, 0.0);
}

}  // namespace
}  // namespace gk
