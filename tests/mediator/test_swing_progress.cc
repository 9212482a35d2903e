// The swing progress the mediator hands to the foot lock advances every frame, also with clips
// of fewer frames per second than the simulation: the release of a lifted foot follows it, and
// a progress that stood still every other frame carried the foot in jerks.

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "mediator/mediator.h"
#include "tests/mediator/mediator_fixture.h"
#include "tests/test_data.h"

namespace gk {
namespace {

constexpr float kDt = 1.0f / 60.0f;

// One agent walking straight at the clip's own speed for `frames` frames at 60 Hz; `each` sees the
// frame index, the plans and the agent's slot.
template <typename Each>
void walk_steadily(const LocomotionLibrary& lib, int frames, Each each) {
  const float speed = lib.clips[lib.groups[lib.forward_group].clips.front()].speed_m_s;
  Mediator m(lib, MediatorParams{}, 1);
  const uint32_t id = 1;
  glm::vec2 pos(0.0f), vel(0.0f, speed);
  const float theta = 0.0f;
  for (int f = 0; f < frames; ++f) {
    pos += vel * kDt;
    ASSERT_TRUE(m.plan(AgentFrame{{&id, 1}, {&pos, 1}, {&vel, 1}, {&theta, 1}}, kDt).ok());
    each(f, m.plans(), m.plans().slot_of_agent[0]);
  }
}

TEST(SwingProgress, AdvancesEveryFrameWithA30FpsClip) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_15_walk_mrl30.bvh");
  auto lib = test::load_data_library({"clips/bvh/more/cmu_16_15_walk_mrl30.bvh"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  ASSERT_FLOAT_EQ(lib->clips[lib->groups[lib->forward_group].clips.front()].clip.fps, 30.0f);
  float prev[2] = {-1.0f, -1.0f};
  int swinging = 0, stalled = 0;
  walk_steadily(*lib, 240, [&](int f, const AnimationPlans& pl, int slot) {
    for (int s = 0; s < 2; ++s) {
      const float p = pl.swing_progress[s][slot];
      // Mid-swing, after the blend has settled on the walk (the first second).
      if (f >= 60 && p > 0.05f && p < 0.95f && prev[s] > 0.05f && prev[s] < 0.95f) {
        ++swinging;
        if (std::abs(p - prev[s]) < 1e-6f) ++stalled;
      }
      prev[s] = p;
    }
  });
  EXPECT_GT(swinging, 40);
  EXPECT_EQ(stalled, 0) << "of " << swinging << " mid-swing frames";
}

// The landing time the plans give for a foot in the air (what pose synthesis places a new agent's
// support foot by) is when the plans do bring it down, walking steadily: the first frame its
// swing progress is back to 0.
TEST(SwingProgress, LandingTimeIsWhenTheFootComesDown) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_15_walk_mrl30.bvh");
  auto lib = test::load_data_library({"clips/bvh/more/cmu_16_15_walk_mrl30.bvh"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  constexpr int kFrames = 300;
  std::vector<float> progress[2], landing[2];
  walk_steadily(*lib, kFrames, [&](int, const AnimationPlans& pl, int slot) {
    for (int s = 0; s < 2; ++s) {
      progress[s].push_back(pl.swing_progress[s][slot]);
      landing[s].push_back(pl.landing_s[s][slot]);
    }
  });
  int compared = 0;
  for (int s = 0; s < 2; ++s) {
    for (int f = 60; f < kFrames; ++f) {
      if (progress[s][f] <= 0.0f) {
        EXPECT_LT(landing[s][f], 0.0f) << f;  // on the ground: no landing to come
        continue;
      }
      int down = f + 1;
      while (down < kFrames && progress[s][down] > 0.0f) ++down;
      if (down == kFrames) break;
      // Within a frame of the clip (30 fps) and one of the simulation: the plans take the
      // nearest clip frame, and the foot is down from the first frame after the swing's end.
      constexpr float kTolerance = 1.0f / 30.0f + kDt;
      const float actual = static_cast<float>(down - f) * kDt;
      EXPECT_NEAR(landing[s][f], actual, kTolerance) << "frame " << f << " foot " << s;
      ++compared;
    }
  }
  EXPECT_GT(compared, 80);
}

}  // namespace
}  // namespace gk
