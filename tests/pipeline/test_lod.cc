// Level of detail (pipeline/lod.h): levels by distance with hysteresis, agents of a level spread
// evenly over its period, full-detail agents posed exactly as without LOD, distant agents whose
// phase advances and whose body follows the simulator between updates, and level changes without
// joint jumps beyond what the agent's own motion explains.

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "animation/pose_jobs.h"
#include "pipeline/crowd_pipeline.h"
#include "pipeline/lod.h"
#include "tests/mediator/mediator_fixture.h"
#include "tests/mediator/scripted_crowd.h"
#include "tests/pipeline/allocation_counter.h"
#include "tests/test_data.h"

namespace gk {
namespace {

constexpr float kDt = 1.0f / 60.0f;

PipelineOptions options(size_t capacity) {
  return test::test_pipeline_options(capacity, kDt, /*make_palettes=*/true,
                                     /*record_metrics=*/false);
}

LodParams lod_at(glm::vec2 focus, float d0, float d1, float d2, float hysteresis = 2.0f) {
  LodParams p;
  p.enabled = true;
  p.focus = focus;
  p.distances_m = {d0, d1, d2};
  p.hysteresis_m = hysteresis;
  return p;
}

TEST(LodPolicy, LevelsByDistanceWithHysteresis) {
  const LodParams p = lod_at({0.0f, 0.0f}, 10.0f, 20.0f, 40.0f, 2.0f);
  EXPECT_EQ(LodPolicy::level_of(0.0f, p), 0);
  EXPECT_EQ(LodPolicy::level_of(9.9f, p), 0);
  EXPECT_EQ(LodPolicy::level_of(10.0f, p), 1);
  EXPECT_EQ(LodPolicy::level_of(25.0f, p), 2);
  EXPECT_EQ(LodPolicy::level_of(1e6f, p), 3);
  // Walking out across the first boundary: still 0 within the hysteresis, 1 past it.
  EXPECT_EQ(LodPolicy::next_level(0, 11.9f, p), 0);
  EXPECT_EQ(LodPolicy::next_level(0, 12.1f, p), 1);
  // And back: 1 until 2 m inside.
  EXPECT_EQ(LodPolicy::next_level(1, 8.1f, p), 1);
  EXPECT_EQ(LodPolicy::next_level(1, 7.9f, p), 0);
  // A jump over several boundaries lands on the right level at once.
  EXPECT_EQ(LodPolicy::next_level(0, 100.0f, p), 3);
  EXPECT_EQ(LodPolicy::next_level(3, 1.0f, p), 0);
}

TEST(LodPolicy, AnAgentOnABoundaryDoesNotFlicker) {
  const LodParams p = lod_at({0.0f, 0.0f}, 10.0f, 20.0f, 40.0f, 1.0f);
  AnimationPlans plans;
  plans.agent_of_slot = {0};
  plans.root_xz = {glm::vec2(0.0f, 9.0f)};
  LodPolicy policy(1);
  policy.assign(plans, p, 0);
  ASSERT_EQ(policy.level(0), 0);
  // Jitter of +-0.6 m about the boundary: no level change.
  int changes = 0, last = 0;
  for (int f = 1; f < 200; ++f) {
    plans.root_xz[0].y = 10.0f + 0.6f * std::sin(0.7f * static_cast<float>(f));
    policy.assign(plans, p, f);
    changes += policy.level(0) != last;
    last = policy.level(0);
  }
  EXPECT_EQ(changes, 0);
  EXPECT_EQ(policy.counts()[0], 1);
}

TEST(LodPolicy, AgentsOfALevelAreSpreadEvenlyOverItsPeriod) {
  const size_t n = 1000;
  const LodParams p = lod_at({0.0f, 0.0f}, 1.0f, 2.0f, 3.0f);
  AnimationPlans plans;
  plans.agent_of_slot.resize(n);
  plans.root_xz.resize(n);
  for (size_t s = 0; s < n; ++s) {
    plans.agent_of_slot[s] = static_cast<int32_t>(s);
    // A quarter per level, interleaved.
    plans.root_xz[s] = glm::vec2(0.5f + static_cast<float>(s % 4), 0.0f);
  }
  LodPolicy policy(n);
  std::vector<int> updates(n, 0);
  for (int f = 0; f < 8; ++f) {
    policy.assign(plans, p, f);
    std::array<int, kNumLodLevels> due{};
    for (size_t s = 0; s < n; ++s) {
      due[policy.level(static_cast<int>(s))] += policy.due()[s];
      updates[s] += policy.due()[s];
      const auto detail = static_cast<PoseDetail>(policy.pose_detail()[s]);
      if (!policy.due()[s]) {
        EXPECT_EQ(detail, PoseDetail::kHold);
      }
    }
    for (int level = 0; level < kNumLodLevels; ++level) {
      EXPECT_EQ(policy.counts()[level], 250);
      // 250 agents over a period of P frames: 250 / P each frame, give or take one.
      EXPECT_NEAR(due[level], 250.0 / kLodPeriod[level], 1.0)
          << "level " << level << " frame " << f;
    }
  }
  // Over 8 frames every agent is updated exactly 8 / period times.
  for (size_t s = 0; s < n; ++s) {
    EXPECT_EQ(updates[s], 8 / kLodPeriod[policy.level(static_cast<int>(s))]) << "slot " << s;
  }
}

TEST(LodPolicy, ParametersAreChecked) {
  LodParams p;
  EXPECT_TRUE(validate(p).ok());
  EXPECT_TRUE(parse_lod_distances("5,10.5,20", "--lod-distances", &p).ok());
  EXPECT_FLOAT_EQ(p.distances_m[1], 10.5f);
  const Status decreasing = parse_lod_distances("5,4,20", "--lod-distances", &p);
  EXPECT_FALSE(decreasing.ok());
  EXPECT_NE(decreasing.message().find("--lod-distances"), std::string::npos);
  EXPECT_FLOAT_EQ(p.distances_m[1], 10.5f);  // unchanged on error
  EXPECT_FALSE(parse_lod_distances("5,10", "--lod-distances", &p).ok());
  EXPECT_FALSE(parse_lod_distances("5,x,10", "--lod-distances", &p).ok());
  EXPECT_FALSE(parse_lod_distances("5,10,20,30", "--lod-distances", &p).ok());
  p.hysteresis_m = -1.0f;
  EXPECT_FALSE(validate(p).ok());
  CrowdPipeline pipeline(test::builtin_library(), MediatorParams{}, options(1));
  EXPECT_FALSE(pipeline.set_lod(p).ok());
  EXPECT_FALSE(pipeline.lod_params().enabled);
}

// Walkers near the focus (level 0) and far from it: the near ones' poses are bit for bit those of
// a run without LOD, frame after frame.
TEST(CrowdPipelineLod, FullDetailAgentsArePosedExactlyAsWithoutLod) {
  const LocomotionLibrary& lib = test::builtin_library();
  std::vector<test::Script> scripts;
  for (int i = 0; i < 4; ++i) scripts.push_back(test::straight({1.5f * i, -3.0f}, {0.1f, 1.3f}));
  for (int i = 0; i < 12; ++i) {
    scripts.push_back(test::straight({60.0f + 1.5f * i, 0.0f}, {0.0f, 1.1f + 0.05f * i}));
  }
  test::ScriptedCrowd with(scripts), without(scripts);
  CrowdPipeline lod(lib, MediatorParams{}, options(scripts.size()));
  CrowdPipeline full(lib, MediatorParams{}, options(scripts.size()));
  ASSERT_TRUE(lod.set_lod(lod_at({0.0f, 0.0f}, 20.0f, 30.0f, 40.0f)).ok());
  int held = 0;
  for (int f = 0; f < 240; ++f) {
    ASSERT_TRUE(lod.step(with, kDt).ok());
    ASSERT_TRUE(full.step(without, kDt).ok());
    lod.update_palettes();
    full.update_palettes();
    for (size_t i = 0; i < scripts.size(); ++i) {
      const int slot = lod.plans().slot_of_agent[i];
      ASSERT_EQ(slot, full.plans().slot_of_agent[i]);
      if (i < 4) {
        ASSERT_EQ(lod.lod().level(slot), 0);
        EXPECT_TRUE(lod.lod().full_detail()[slot]);
        const auto a = lod.poses().world(slot), b = full.poses().world(slot);
        ASSERT_TRUE(std::equal(a.begin(), a.end(), b.begin())) << "agent " << i << " frame " << f;
        const auto pa = lod.poses().palette(slot), pb = full.poses().palette(slot);
        ASSERT_TRUE(std::equal(pa.begin(), pa.end(), pb.begin()));
      } else if (f > 0) {  // a newcomer takes its level the frame after it came
        ASSERT_EQ(lod.lod().level(slot), 3);
        EXPECT_FALSE(lod.lod().full_detail()[slot]);
        held += !lod.lod().due()[slot];
      }
    }
  }
  EXPECT_GT(held, 0);  // the far agents were really left out on most frames
}

// A distant agent between its updates: the gait phase advances every frame at the planned rate,
// the drawn root stays on the simulator's position, and the whole body moves with it.
TEST(CrowdPipelineLod, DistantAgentsPhaseAdvancesAndRootFollowsBetweenUpdates) {
  const LocomotionLibrary& lib = test::builtin_library();
  test::ScriptedCrowd crowd({test::straight({100.0f, 0.0f}, {0.0f, 1.3f})});
  CrowdPipeline pipeline(lib, MediatorParams{}, options(1));
  ASSERT_TRUE(pipeline.set_lod(lod_at({0.0f, 0.0f}, 10.0f, 20.0f, 40.0f)).ok());
  const int hips = lib.skeleton->role(JointRole::kHips);
  for (int f = 0; f < 60; ++f) ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
  int held = 0;
  for (int f = 0; f < 120; ++f) {
    const float phase_before = pipeline.plans().phase[0];
    const glm::vec3 hips_before = pipeline.poses().joint_position(0, hips);
    const std::vector<glm::mat4> world_before(pipeline.poses().world(0).begin(),
                                              pipeline.poses().world(0).end());
    const glm::vec2 root_before = pipeline.plans().root_xz[0];
    ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
    ASSERT_EQ(pipeline.lod().level(0), 3);
    const AnimationPlans& pl = pipeline.plans();
    // The rate of the last plan: phase per frame = rate * dt / cycle of the (walking) blend.
    float advance = pl.phase[0] - phase_before;
    if (advance < 0.0f) advance += 1.0f;
    EXPECT_GT(advance, 0.0f) << "frame " << f;
    EXPECT_LT(advance, 0.1f);
    // The root stays on the simulator's position (the mediator's pull keeps it within 6 cm).
    EXPECT_LT(glm::length(pl.root_xz[0] - pipeline.frame().positions[0]), 0.061f);
    if (!pipeline.lod().due()[0]) {
      ++held;
      // The held body is drawn moved exactly with the root, by its root offset alone: the posed
      // joints are not rewritten (a held agent costs O(1)).
      const auto world = pipeline.poses().world(0);
      EXPECT_TRUE(std::equal(world.begin(), world.end(), world_before.begin()));
      const glm::vec3 moved = pipeline.poses().joint_position(0, hips) - hips_before;
      const glm::vec2 root_moved = pl.root_xz[0] - root_before;
      EXPECT_NEAR(moved.x, root_moved.x, 1e-4f);
      EXPECT_NEAR(moved.z, root_moved.y, 1e-4f);
      EXPECT_NEAR(moved.y, 0.0f, 1e-6f);
      EXPECT_GT(glm::length(root_moved), 0.5f * 1.3f * kDt);
    } else {
      EXPECT_EQ(pipeline.poses().root_offset(0), glm::vec2(0.0f));  // posed where it is
    }
  }
  EXPECT_EQ(held, 120 - 120 / 8);
}

// The largest distance any joint moves from one frame to the next [m].
float max_joint_step(std::span<const glm::vec3> a, std::span<const glm::vec3> b) {
  float d = 0.0f;
  for (size_t j = 0; j < a.size(); ++j) d = std::max(d, glm::length(a[j] - b[j]));
  return d;
}

// A slot's joints as drawn this frame (held poses moved on by their root offset).
std::vector<glm::vec3> drawn_joints(const PoseSynthesizer& poses, int slot) {
  std::vector<glm::vec3> out(poses.num_joints());
  for (int j = 0; j < poses.num_joints(); ++j) out[j] = poses.joint_position(slot, j);
  return out;
}

// A walker coming from far away to the focus and on past it crosses every level boundary twice.
// Without LOD, its largest joint step from one frame to the next (a swinging foot) is one frame of
// its motion, M, itself within what a walk at speed s allows (kLimbSpeedFactor * s +
// kLimbSpeedMargin per second). With LOD no joint may move from one frame to the next by more than
// the frames since the agent's last update times M (to 10%), plus kLevelChangeSlack where levels 1
// and 2 or 2 and 3 meet (the coarse joints). Entering or leaving level 0 gets no slack: the foot
// locks start from the feet as drawn, and are let go through their releases, not at once.
void expect_no_joint_jumps(const LocomotionLibrary& lib) {
  constexpr float kLimbSpeedFactor = 6.0f;
  constexpr float kLimbSpeedMargin = 0.5f;    // [m/s]
  constexpr float kLevelChangeSlack = 0.03f;  // [m]
  // The two runs' feet lock at slightly different moments (with LOD the locks start afresh on
  // entering level 0), so the largest step of one is the other's to within this factor.
  constexpr float kMotionMargin = 1.1f;
  const float speed = 1.4f;
  float frame_motion = 0.0f;  // M [m]
  for (bool use_lod : {false, true}) {
    SCOPED_TRACE(use_lod ? "LOD" : "no LOD");
    test::ScriptedCrowd crowd({test::straight({0.5f, -40.0f}, {0.0f, speed})});
    CrowdPipeline pipeline(lib, MediatorParams{}, options(1));
    if (use_lod) {
      ASSERT_TRUE(pipeline.set_lod(lod_at({0.0f, 0.0f}, 8.0f, 16.0f, 28.0f)).ok());
    }
    std::vector<glm::vec3> last;
    int frames_since_update = 1, changes = 0, last_level = -1;
    for (int f = 0; f < 60 * 55; ++f) {
      ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
      const std::vector<glm::vec3> world = drawn_joints(pipeline.poses(), 0);
      const int level = pipeline.lod().level(0);
      const bool changed = last_level >= 0 && level != last_level;
      // The first second is the walker's start (it is fresh, standing, then walking).
      if (!last.empty() && f > 60) {
        const float step = max_joint_step(world, last);
        if (!use_lod) {
          frame_motion = std::max(frame_motion, step);
        } else {
          const bool level0_change = changed && std::min(level, last_level) == 0;
          const float bound =
              static_cast<float>(frames_since_update) * kMotionMargin * frame_motion +
              (changed && !level0_change ? kLevelChangeSlack : 0.0f);
          size_t worst = 0;
          for (size_t j = 0; j < world.size(); ++j) {
            if (glm::length(world[j] - last[j]) > glm::length(world[worst] - last[worst]))
              worst = j;
          }
          {
            ASSERT_LE(step, bound) << "joint " << lib.skeleton->names[worst] << " frame " << f
                                   << " level " << level << " (was " << last_level << ", "
                                   << frames_since_update << " frames since the last update)";
          }
        }
      }
      changes += changed && f > 1;  // frame 1: the newcomer takes its level
      last_level = level;
      const bool updated = !use_lod || pipeline.lod().due()[0];
      frames_since_update = updated ? 1 : frames_since_update + 1;
      last = world;
    }
    if (!use_lod) {
      EXPECT_GT(frame_motion, speed * kDt);
      EXPECT_LE(frame_motion, kDt * (kLimbSpeedFactor * speed + kLimbSpeedMargin));
    } else {
      EXPECT_EQ(changes, 6);  // 3 -> 2 -> 1 -> 0 -> 1 -> 2 -> 3
    }
  }
}

TEST(CrowdPipelineLod, LevelChangesCauseNoJointJumps) {
  expect_no_joint_jumps(test::builtin_library());
}

// The same with the 53-joint mannequin, whose fingers and toes levels 2 and 3 leave out (they
// follow their parents in the standing pose there): entering and leaving those levels moves them
// no more than the slack. Its foot locks hold larger IK offsets than the built-in clips' (a reset
// on leaving level 0 snapped a foot about 8 cm): they are let go through their releases.
TEST(CrowdPipelineLod, LevelChangesCauseNoJointJumpsWithCoarseJoints) {
  GK_REQUIRE_DATA("clips/gltf/ual_mannequin_quaternius.glb");
  auto lib = test::load_data_library({"clips/gltf/ual_mannequin_quaternius.glb"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  expect_no_joint_jumps(*lib);
}

// Per-frame code allocates nothing, with LOD too (walkers over every level, metrics on, palettes).
TEST(CrowdPipelineLod, StepAllocatesNothing) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  std::vector<test::Script> scripts;
  for (int i = 0; i < 16; ++i) scripts.push_back(test::straight({1.5f * i, 0.0f}, {0.0f, 1.4f}));
  test::ScriptedCrowd crowd(scripts, /*honour_feedback=*/true);
  PipelineOptions o = options(16);
  o.record_metrics = true;
  CrowdPipeline pipeline(test::builtin_library(), MediatorParams{}, o);
  ASSERT_TRUE(pipeline.set_lod(lod_at({0.0f, 0.0f}, 5.0f, 10.0f, 15.0f)).ok());
  for (int f = 0; f < 30; ++f) ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
  for (int level = 0; level < kNumLodLevels; ++level) EXPECT_GT(pipeline.lod().counts()[level], 0);
  const int64_t before = test::allocations_so_far();
  for (int f = 0; f < 60; ++f) {
    ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
    pipeline.update_palettes();
  }
  EXPECT_EQ(test::allocations_so_far() - before, 0);
}

}  // namespace
}  // namespace gk
