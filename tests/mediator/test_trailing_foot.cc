// A walker's trailing foot keeps its weight, pinned, until the leading one is flat (pose
// synthesis's other_on_heel): the leading foot as it is drawn, not as the blended clips have it.
// A walk blended with the standing pose (a creeping pedestrian) puts a planted toe above its heel;
// judged on that pose, a leading foot pinned flat counted as still on its heel, and the trailing
// foot stayed pinned while the clips swung it, its ball rising with theirs (in ETH's hotel replay
// with the mannequin: up to 17 cm, for 26 frames).

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "mediator/mediator.h"
#include "mediator/pose_synthesis.h"
#include "tests/mediator/mediator_fixture.h"
#include "tests/test_data.h"

namespace gk {
namespace {

constexpr float kDt = 1.0f / 60.0f;

// Pedestrians creeping and walking slowly (0.1-0.6 m/s, speeding up and slowing down, each on its
// own phase): the frames on which a foot stays pinned after the clips have lifted it (their hold
// vote gone) are at most a double support: about 10% of a gait cycle (GAIT.md) at the slowest the
// clips are played, the time a leading foot takes to come down flat.
TEST(TrailingFoot, WaitsNoLongerThanADoubleSupportForALeadingFootDrawnFlat) {
  GK_REQUIRE_DATA("clips/gltf/ual_mannequin_quaternius.glb");
  auto lib = test::load_data_library({"clips/gltf/ual_mannequin_quaternius.glb"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  const MediatorParams params;
  const LocomotionClip& walk = lib->clips[lib->groups[lib->forward_group].clips.front()];
  ASSERT_TRUE(walk.double_support);
  const float double_support_s = 0.1f * walk.cycle_s / params.min_playback_rate;
  constexpr int kAgents = 16;
  Mediator m(*lib, params, kAgents);
  PoseSynthesizer ps(*lib, kAgents, false);
  test::AgentRow row(kAgents);
  std::vector<int> held(kAgents * 2, 0);
  int longest = 0, lifted_frames = 0;
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
    for (int i = 0; i < kAgents; ++i) {
      const int slot = m.plans().slot_of_agent[i];
      for (int s = 0; s < 2; ++s) {
        const bool lifted = m.plans().hold[s][slot] < 0.5f;
        lifted_frames += lifted;
        const bool pinned = ps.foot_locks().lock[static_cast<size_t>(slot) * 2 + s].state ==
                            FootLockState::kLocked;
        int& run = held[i * 2 + s];
        run = lifted && pinned ? run + 1 : 0;
        longest = std::max(longest, run);
      }
    }
  }
  ASSERT_GT(lifted_frames, 1000) << "the walkers need to step";
  EXPECT_LE(static_cast<float>(longest) * kDt, double_support_s)
      << longest << " frames against a double support of " << double_support_s << " s";
}

}  // namespace
}  // namespace gk
