// CrowdPipeline: the order of the frame (the snapshot is the frame as planned, before feedback),
// a failed frame leaving the last good one drawable, the compare lane's follow(), palettes in
// slot order, hooks, and no allocation per frame.

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "pipeline/crowd_pipeline.h"
#include "tests/mediator/mediator_fixture.h"
#include "tests/mediator/scripted_crowd.h"
#include "tests/pipeline/allocation_counter.h"

namespace gk {
namespace {

constexpr float kDt = 1.0f / 60.0f;

std::vector<test::Script> walkers(int n, float speed) {
  std::vector<test::Script> s;
  for (int i = 0; i < n; ++i) s.push_back(test::straight({1.5f * i, 0.0f}, {0.0f, speed}));
  return s;
}

PipelineOptions drawn(size_t capacity) {
  return test::test_pipeline_options(capacity, kDt, /*make_palettes=*/true);
}

// A source that repeats an agent id on chosen frames (a simulator's bug the mediator refuses).
class RepeatingIdCrowd : public test::ScriptedCrowd {
 public:
  using ScriptedCrowd::ScriptedCrowd;
  bool repeat = false;
  AgentFrame frame() const override {
    AgentFrame f = ScriptedCrowd::frame();
    if (!repeat) return f;
    repeated_ = std::vector<uint32_t>(f.ids.begin(), f.ids.end());
    repeated_.back() = repeated_.front();
    f.ids = repeated_;
    return f;
  }

 private:
  mutable std::vector<uint32_t> repeated_;
};

// Issue #11: a failed frame leaves the previous snapshot, plans, poses and palettes intact, and
// drawable; the pipeline carries on with the next good frame.
TEST(CrowdPipeline, FailedFrameLeavesTheLastGoodFrameDrawable) {
  const LocomotionLibrary& lib = test::builtin_library();
  RepeatingIdCrowd crowd(walkers(4, 1.3f));
  CrowdPipeline pipeline(lib, MediatorParams{}, drawn(crowd.capacity()));
  for (int f = 0; f < 40; ++f) ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
  pipeline.update_palettes();
  const AgentFrame frame = pipeline.frame();
  const std::vector<uint32_t> ids(frame.ids.begin(), frame.ids.end());
  const std::vector<glm::vec2> positions(frame.positions.begin(), frame.positions.end());
  const AnimationPlans plans = pipeline.plans();
  const std::vector<glm::mat4> palettes(pipeline.palettes().begin(), pipeline.palettes().end());
  const size_t slots = pipeline.num_slots();
  const int64_t frames = pipeline.frames_run();

  crowd.repeat = true;
  const Status s = pipeline.step(crowd, kDt);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("appears twice"), std::string::npos) << s.message();
  const AgentFrame after = pipeline.frame();
  EXPECT_EQ(std::vector<uint32_t>(after.ids.begin(), after.ids.end()), ids);
  EXPECT_EQ(std::vector<glm::vec2>(after.positions.begin(), after.positions.end()), positions);
  EXPECT_EQ(pipeline.mediator().num_agents(), ids.size());
  EXPECT_EQ(pipeline.plans().slot_of_agent, plans.slot_of_agent);
  EXPECT_EQ(pipeline.plans().root_xz, plans.root_xz);
  EXPECT_EQ(pipeline.plans().layer_weight, plans.layer_weight);
  EXPECT_EQ(pipeline.num_slots(), slots);
  EXPECT_EQ(pipeline.frames_run(), frames);
  // Drawable: every agent of the frame has a finite palette in a slot below num_slots(), the
  // very matrices of the last good frame (the failed frame posed nothing to make them again from).
  pipeline.update_palettes();
  const auto now = pipeline.palettes();
  ASSERT_EQ(now.size(), palettes.size());
  EXPECT_TRUE(std::equal(now.begin(), now.end(), palettes.begin()));
  const size_t J = static_cast<size_t>(pipeline.num_joints());
  for (size_t i = 0; i < after.size(); ++i) {
    const int slot = pipeline.plans().slot_of_agent[i];
    ASSERT_GE(slot, 0);
    ASSERT_LT(static_cast<size_t>(slot), pipeline.num_slots());
    for (size_t j = 0; j < J; ++j) {
      const glm::mat4& m = now[slot * J + j];
      for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) ASSERT_TRUE(std::isfinite(m[c][r]));
      }
    }
  }

  crowd.repeat = false;
  ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
  EXPECT_EQ(pipeline.frames_run(), frames + 1);
  EXPECT_EQ(pipeline.plans().slot_of_agent, plans.slot_of_agent);  // nobody restarted
  for (size_t i = 0; i < pipeline.frame().size(); ++i) {
    EXPECT_EQ(pipeline.plans().fresh[pipeline.plans().slot_of_agent[i]], 0);
  }
}

// The snapshot is the frame as planned: a source that applies feedback in place (AgentFrame is a
// view into its arrays) has changed its own frame by the time the step returns; the pipeline's
// frame, and what the metrics measured, are the values the mediator planned.
TEST(CrowdPipeline, SnapshotIsTheFrameBeforeFeedback) {
  const LocomotionLibrary& lib = test::builtin_library();
  // Far beyond the fastest clip (rate and stride limits): feedback slows the agent down.
  test::ScriptedCrowd crowd(walkers(1, 9.0f), /*honour_feedback=*/true);
  CrowdPipeline pipeline(lib, MediatorParams{}, drawn(1));
  ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
  ASSERT_EQ(pipeline.mediator().feedback().has_feedback[0], 1);
  const glm::vec2 fed_back = pipeline.mediator().feedback().velocities[0];
  EXPECT_LT(glm::length(fed_back), 8.0f);
  EXPECT_EQ(crowd.frame().velocities[0], fed_back);  // applied in place
  EXPECT_EQ(pipeline.frame().velocities[0], glm::vec2(0.0f, 9.0f));
  EXPECT_EQ(pipeline.mediator().sim_velocities()[0], glm::vec2(0.0f, 9.0f));
}

// follow(): a second animation of the same frames (the split screen's compare lane) plans the
// leader's frame as planned and sends no feedback.
TEST(CrowdPipeline, FollowAnimatesTheLeadersFrameWithoutFeedback) {
  const LocomotionLibrary& lib = test::builtin_library();
  test::ScriptedCrowd crowd(walkers(3, 9.0f), /*honour_feedback=*/true);
  CrowdPipeline leader(lib, MediatorParams{}, drawn(3));
  MediatorParams naive;
  naive.mode = MediatorMode::kNaive;
  CrowdPipeline follower(lib, naive, drawn(3));
  for (int f = 0; f < 20; ++f) {
    ASSERT_TRUE(leader.step(crowd, kDt).ok());
    const int fed = crowd.last_feedback_count();
    ASSERT_TRUE(follower.follow(leader.frame(), crowd.feedback_policy(), kDt).ok());
    EXPECT_EQ(crowd.last_feedback_count(), fed);  // nothing more reached the source
    for (size_t i = 0; i < 3; ++i) {
      EXPECT_EQ(follower.frame().ids[i], leader.frame().ids[i]);
      EXPECT_EQ(follower.frame().velocities[i], glm::vec2(0.0f, 9.0f));  // not the fed-back v
    }
  }
  EXPECT_EQ(follower.times().sim_ms, 0.0);
  EXPECT_EQ(follower.metrics()->finish().agent_frames, 60);
}

// Palettes stay in slot order: agent i is drawn with block slot_of_agent[i]; num_slots() covers
// every live agent's slot.
TEST(CrowdPipeline, PalettesInSlotOrder) {
  const LocomotionLibrary& lib = test::builtin_library();
  test::ScriptedCrowd crowd(walkers(5, 1.2f));
  CrowdPipeline pipeline(lib, MediatorParams{}, drawn(5));
  for (int f = 0; f < 10; ++f) ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
  pipeline.update_palettes();
  const size_t J = static_cast<size_t>(pipeline.num_joints());
  ASSERT_EQ(pipeline.num_slots(), 5u);
  ASSERT_EQ(pipeline.palettes().size(), 5 * J);
  for (size_t i = 0; i < 5; ++i) {
    const int slot = pipeline.plans().slot_of_agent[i];
    const auto own = pipeline.poses().palette(slot);
    EXPECT_TRUE(std::equal(own.begin(), own.end(), pipeline.palettes().begin() + slot * J));
  }
}

// A step poses the crowd; its skinning palettes (world * inverse bind) are made when they are
// asked for (update_palettes, before an upload): a step alone leaves last frame's, and the update
// makes every agent's from the joints it was posed with.
TEST(CrowdPipeline, PalettesAreMadeFromThePoseWhenAskedFor) {
  const LocomotionLibrary& lib = test::builtin_library();
  test::ScriptedCrowd crowd(walkers(5, 1.2f));
  CrowdPipeline pipeline(lib, MediatorParams{}, drawn(5));
  for (int f = 0; f < 10; ++f) ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
  pipeline.update_palettes();
  const std::vector<glm::mat4> before(pipeline.palettes().begin(), pipeline.palettes().end());
  ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
  EXPECT_TRUE(std::equal(before.begin(), before.end(), pipeline.palettes().begin()));
  pipeline.update_palettes();
  const size_t J = static_cast<size_t>(pipeline.num_joints());
  const auto& inverse_bind = pipeline.poses().inverse_bind();
  int moved = 0;
  for (size_t i = 0; i < 5; ++i) {
    const int slot = pipeline.plans().slot_of_agent[i];
    const auto world = pipeline.poses().world(slot);
    const auto palette = pipeline.poses().palette(slot);
    for (size_t j = 0; j < J; ++j) {
      const glm::mat4 expected = world[j] * inverse_bind[j];
      for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) EXPECT_NEAR(palette[j][c][r], expected[c][r], 1e-5f);
      }
      moved += palette[j] != before[slot * J + j];
    }
  }
  EXPECT_GT(moved, 0);  // walkers: the new palettes are not last frame's
}

// Hooks run once per good frame, after the metrics, and their errors end the step.
TEST(CrowdPipeline, FrameHooks) {
  const LocomotionLibrary& lib = test::builtin_library();
  test::ScriptedCrowd crowd(walkers(2, 1.2f));
  CrowdPipeline pipeline(lib, MediatorParams{}, drawn(2));
  std::vector<int64_t> seen;
  pipeline.add_frame_hook([&](const CrowdPipeline& p) {
    seen.push_back(p.frames_run());
    EXPECT_EQ(p.metrics()->finish().agent_frames, 2 * p.frames_run());
    return p.frames_run() == 3 ? Status::Error("hook: disk full") : Status::Ok();
  });
  EXPECT_TRUE(pipeline.step(crowd, kDt).ok());
  EXPECT_TRUE(pipeline.step(crowd, kDt).ok());
  const Status s = pipeline.step(crowd, kDt);
  EXPECT_EQ(s.message(), "hook: disk full");
  EXPECT_EQ(seen, (std::vector<int64_t>{1, 2, 3}));
}

// The architecture's rule: per-frame code allocates nothing. Whole frames (sim, plan, snapshot,
// feedback, poses, metrics) and their palettes after a warm-up, on one thread.
TEST(CrowdPipeline, StepAllocatesNothing) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const LocomotionLibrary& lib = test::builtin_library();
  test::ScriptedCrowd crowd(walkers(16, 1.4f), /*honour_feedback=*/true);
  CrowdPipeline pipeline(lib, MediatorParams{}, drawn(16));
  for (int f = 0; f < 30; ++f) ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
  const int64_t before = test::allocations_so_far();
  for (int f = 0; f < 60; ++f) {
    ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
    pipeline.update_palettes();
  }
  EXPECT_EQ(test::allocations_so_far() - before, 0);
  // The counter counts (else the test above proves nothing).
  std::string grown(1000, 'x');
  EXPECT_GT(test::allocations_so_far() - before, 0) << grown;
}

}  // namespace
}  // namespace gk
