// A walker's trailing foot keeps its weight, pinned, until the leading one is flat (pose
// synthesis's other_on_heel): the leading foot as it is drawn, not as the blended clips have it.
// A walk blended with the standing pose (a creeping pedestrian) puts a planted toe above its heel;
// judged on that pose, a leading foot pinned flat counted as still on its heel, and the trailing
// foot stayed pinned while the clips swung it, its ball rising with theirs (in ETH's hotel replay
// with the mannequin: up to 17 cm, for 26 frames).
// And while the standing clip votes the feet (the gait clips under a quarter of the blend), a
// creeper's pinned feet stand on the floor where it has them (foot_lock.h,
// FootLockInput::standing_votes). The walk's share of the blend still swings the feet a little,
// and the height a slow walk gives back to a stepping foot lifts them further: a pinned toe that
// rose with that, as a push-off's does, was held still in the air, up to 17 cm above the floor and
// for over half a second, before a re-planting step moved it.

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

// The mannequin's library, and a double support (GAIT.md: about 10% of a gait cycle) of its
// slowest walk at the slowest the clips are played.
struct Creepers {
  LocomotionLibrary lib;
  float double_support_s = 0.0f;
};
Result<Creepers> mannequin_creepers() {
  auto lib = test::load_data_library({"clips/gltf/ual_mannequin_quaternius.glb"});
  if (!lib.ok()) return lib.status();
  const LocomotionClip& walk = lib->clips[lib->groups[lib->forward_group].clips.front()];
  const float ds = 0.1f * walk.cycle_s / MediatorParams{}.min_playback_rate;
  return Creepers{std::move(*lib), ds};
}

// Pedestrians creeping and walking slowly (0.1-0.6 m/s, speeding up and slowing down, each on its
// own phase): the frames on which a foot stays pinned after the clips have lifted it (their hold
// vote gone) are at most a double support: about 10% of a gait cycle (GAIT.md) at the slowest the
// clips are played, the time a leading foot takes to come down flat.
TEST(TrailingFoot, WaitsNoLongerThanADoubleSupportForALeadingFootDrawnFlat) {
  GK_REQUIRE_DATA("clips/gltf/ual_mannequin_quaternius.glb");
  auto creepers = mannequin_creepers();
  ASSERT_TRUE(creepers.ok()) << creepers.message();
  const LocomotionLibrary* lib = &creepers->lib;
  ASSERT_TRUE(lib->clips[lib->groups[lib->forward_group].clips.front()].double_support);
  const float double_support_s = creepers->double_support_s;
  constexpr int kAgents = 16;
  std::vector<int> held(kAgents * 2, 0);
  int longest = 0, lifted_frames = 0;
  ASSERT_TRUE(
      test::creep_row(*lib, kAgents, 8.0f, [&](const Mediator& m, const PoseSynthesizer& ps) {
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
      }));
  ASSERT_GT(lifted_frames, 1000) << "the walkers need to step";
  EXPECT_LE(static_cast<float>(longest) * kDt, double_support_s)
      << longest << " frames against a double support of " << double_support_s << " s";
}

// Sixteen mannequin pedestrians creeping and walking slowly, speeding up and slowing down, each on
// its own phase (as above). Over the frames a foot is pinned while the standing clip votes
// the feet: the toe's height above where the standing clip has it is a few millimetres on average
// (it was 2.6 cm), and one raised by the gait clips before their share fell (a push-off, a trailing
// foot waiting for the leading one) comes down within a double support (GAIT.md: about 10% of a
// cycle, at the slowest the clips are played), not held up until a re-planting step.
TEST(StandingVote, ACreepersPinnedToesStandOnTheFloor) {
  GK_REQUIRE_DATA("clips/gltf/ual_mannequin_quaternius.glb");
  auto creepers = mannequin_creepers();
  ASSERT_TRUE(creepers.ok()) << creepers.message();
  const LocomotionLibrary* lib = &creepers->lib;
  const float double_support_s = creepers->double_support_s;
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
  std::vector<int> run(kAgents * 2, 0);
  int longest = 0, frames = 0;
  double sum_above = 0.0;
  ASSERT_TRUE(
      test::creep_row(*lib, kAgents, 8.0f, [&](const Mediator& m, const PoseSynthesizer& ps) {
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
            if (ps.foot_locks().lock[k].state != FootLockState::kLocked ||
                moving >= kGaitVoteWeight) {
              r = 0;
              continue;
            }
            ++frames;
            const float above = std::max(
                0.0f, ps.foot_locks().drawn_toe[k].y - lib->planted_toe_m[s] - stand_top[s]);
            sum_above += above;
            r = above > 0.02f ? r + 1 : 0;  // visibly off the floor
            longest = std::max(longest, r);
          }
        }
      }));
  ASSERT_GT(frames, 1000) << "the creepers need to stand on pinned feet";
  EXPECT_LT(sum_above / frames, 0.01) << "mean height of a pinned toe above the standing clip's";
  EXPECT_LE(static_cast<float>(longest) * kDt, double_support_s)
      << longest << " frames more than 2 cm up, against a double support of " << double_support_s
      << " s";
}

}  // namespace
}  // namespace gk
