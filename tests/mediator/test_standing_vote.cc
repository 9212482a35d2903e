// A pedestrian creeping (0.1-0.6 m/s: the gait clips carry under a quarter of the blend and the
// standing clip votes both feet down) keeps its pinned feet on the floor where the standing clip
// has them (foot_lock.h, FootLockInput::standing_votes). The walk's share of the blend still
// swings the feet a little, and the height a slow walk gives back to a stepping foot lifts them
// further: a pinned toe that rose with that, as a push-off's does, was held still in the air, up
// to 17 cm above the floor and for over half a second, before a re-planting step moved it.

#include <algorithm>
#include <vector>

#include <gtest/gtest.h>

#include "mediator/mediator.h"
#include "mediator/pose_synthesis.h"
#include "tests/mediator/mediator_fixture.h"
#include "tests/test_data.h"

namespace gk {
namespace {

constexpr float kDt = 1.0f / 60.0f;

// Sixteen mannequin pedestrians creeping and walking slowly, speeding up and slowing down, each on
// its own phase (as TrailingFoot's). Over the frames a foot is pinned while the standing clip votes
// the feet: the toe's height above where the standing clip has it is a few millimetres on average
// (it was 2.6 cm), and one raised by the gait clips before their share fell (a push-off, a trailing
// foot waiting for the leading one) comes down within a double support (GAIT.md: about 10% of a
// cycle, at the slowest the clips are played), not held up until a re-planting step.
TEST(StandingVote, ACreepersPinnedToesStandOnTheFloor) {
  GK_REQUIRE_DATA("clips/gltf/ual_mannequin_quaternius.glb");
  auto lib = test::load_data_library({"clips/gltf/ual_mannequin_quaternius.glb"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  const MediatorParams params;
  const LocomotionClip& walk = lib->clips[lib->groups[lib->forward_group].clips.front()];
  const float double_support_s = 0.1f * walk.cycle_s / params.min_playback_rate;
  // Where the standing clips have each toe, above the library's floor, at its highest.
  float stand_top[2] = {0.0f, 0.0f};
  for (const LocomotionClip& c : lib->clips) {
    if (c.gait || c.transition) continue;
    for (int s = 0; s < 2; ++s) {
      for (float h : c.toe_height_m[s]) {
        stand_top[s] = std::max(stand_top[s], h + c.toe_floor_m[s] - lib->planted_toe_m[s]);
      }
    }
  }
  constexpr int kAgents = 16;
  Mediator m(*lib, params, kAgents);
  PoseSynthesizer ps(*lib, kAgents, false);
  test::AgentRow row(kAgents);
  std::vector<int> run(kAgents * 2, 0);
  int longest = 0, frames = 0;
  double sum_above = 0.0;
  for (int f = 0; f < static_cast<int>(8.0f / kDt); ++f) {
    for (int i = 0; i < kAgents; ++i) {
      const float t = static_cast<float>(f) * kDt;
      const float speed = 0.1f + 0.25f * (1.0f + std::sin(0.8f * t + static_cast<float>(i)));
      row.v[i] = glm::vec2(0.0f, speed);
      row.p[i] += row.v[i] * kDt;
    }
    ASSERT_TRUE(m.plan(row.frame(), kDt).ok());
    ps.run(m.plans(), kAgents, m.params(), kDt);
    if (f < static_cast<int>(1.0f / kDt)) continue;  // settling in
    const AnimationPlans& pl = m.plans();
    for (int i = 0; i < kAgents; ++i) {
      const int slot = pl.slot_of_agent[i];
      float moving = 0.0f;  // the share of the clips that step the feet
      for (int k = 0; k < kMaxBlendLayers; ++k) {
        const LocomotionClip& c = lib->clips[pl.layer_clip[slot * kMaxBlendLayers + k]];
        if (c.gait || c.transition) moving += pl.layer_weight[slot * kMaxBlendLayers + k];
      }
      for (int s = 0; s < 2; ++s) {
        const size_t k = static_cast<size_t>(slot) * 2 + s;
        int& r = run[i * 2 + s];
        if (ps.foot_locks().lock[k].state != FootLockState::kLocked || moving >= kGaitVoteWeight) {
          r = 0;
          continue;
        }
        ++frames;
        const float above =
            std::max(0.0f, ps.foot_locks().drawn_toe[k].y - lib->planted_toe_m[s] - stand_top[s]);
        sum_above += above;
        r = above > 0.02f ? r + 1 : 0;  // visibly off the floor
        longest = std::max(longest, r);
      }
    }
  }
  ASSERT_GT(frames, 1000) << "the creepers need to stand on pinned feet";
  EXPECT_LT(sum_above / frames, 0.01) << "mean height of a pinned toe above the standing clip's";
  EXPECT_LE(static_cast<float>(longest) * kDt, double_support_s)
      << longest << " frames more than 2 cm up, against a double support of " << double_support_s
      << " s";
}

}  // namespace
}  // namespace gk
