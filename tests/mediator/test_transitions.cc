// Starts and stops played from real transition clips (issue #10, item 2): the library keeps the
// start and stop found in the subject-16 takes as transitions, and an agent that starts from rest
// or comes to rest plays them, its feet planted and its root where the simulator has it. A
// library without transitions plays none.

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "mediator/mediator.h"
#include "mediator/mediator_passes.h"
#include "tests/mediator/mediator_fixture.h"
#include "tests/test_data.h"

namespace gk {
namespace {

constexpr float kDt = 1.0f / 60.0f;

// The steady walk, the start take and the stop take of subject 16.
Result<LocomotionLibrary> start_stop_library() {
  return test::load_data_library({"clips/bvh/more/cmu_16_15_walk_mrl30.bvh",
                                  "clips/bvh/more/cmu_16_31_start_walk_mrl30.bvh",
                                  "clips/bvh/more/cmu_16_33_slow_walk_stop_mrl30.bvh"});
}

// Stands for 1 s, speeds up to 1.2 m/s over 1.2 s (along +z), walks on.
glm::vec2 starting(double t) {
  const double u = std::clamp((t - 1.0) / 1.2, 0.0, 1.0);
  return {0.0f, static_cast<float>(1.2 * u * u * (3.0 - 2.0 * u))};
}
// Walks at 1.1 m/s for 2 s, slows to rest over 1.2 s, stands.
glm::vec2 stopping(double t) {
  const double u = std::clamp((t - 2.0) / 1.2, 0.0, 1.0);
  return {0.0f, static_cast<float>(1.1 * (1.0 - u * u * (3.0 - 2.0 * u)))};
}

// Comes to rest as `stopping` does, stands 0.3 s and sets off again as `starting` does: it stands
// for less time than the stop clip takes to settle and fade out.
glm::vec2 stop_and_go(double t) { return t < 3.5 ? stopping(t) : starting(t - 2.5); }

struct Played {
  MetricsReport report;
  std::array<uint64_t, kNumCounts> counts{};
  int frames_with[2] = {0, 0};  // frames a start / stop clip had weight (as a layer)
  float max_weight[2] = {0.0f, 0.0f};
  int pops = 0;
};

Played play(const LocomotionLibrary& lib, glm::vec2 (*velocity)(double), int frames) {
  test::ScriptedCrowd crowd({{glm::vec2(0.0f), velocity, nullptr}});
  CrowdPipeline pipeline(lib, MediatorParams{}, test::test_pipeline_options(1, kDt));
  Played out;
  for (int f = 0; f < frames; ++f) {
    const Status s = pipeline.step(crowd, kDt);
    EXPECT_TRUE(s.ok()) << s.message();
    const AnimationPlans& pl = pipeline.mediator().plans();
    const int slot = pl.slot_of_agent[0];
    // A pop (METRICS.md): a joint turning further in a frame than twice the clips ever do.
    if (pipeline.poses().max_rotation_change(slot) > 2.0f * lib.max_rotation_step_rad) ++out.pops;
    for (int k = 0; k < kMaxBlendLayers; ++k) {
      const int clip = pl.layer_clip[slot * kMaxBlendLayers + k];
      const float w = pl.layer_weight[slot * kMaxBlendLayers + k];
      if (!lib.clips[clip].transition || w <= 0.0f) continue;
      const auto it = std::find_if(lib.transitions.begin(), lib.transitions.end(),
                                   [&](const Transition& t) { return t.clip == clip; });
      EXPECT_NE(it, lib.transitions.end()) << "a transition clip played that no transition owns";
      if (it == lib.transitions.end()) continue;
      const int kind = it->kind == TransitionKind::kStart ? 0 : 1;
      ++out.frames_with[kind];
      out.max_weight[kind] = std::max(out.max_weight[kind], w);
      // Its clock stays within the clip.
      const float t = pl.layer_time_s[slot * kMaxBlendLayers + k];
      EXPECT_GE(t, 0.0f);
      EXPECT_LE(t, it->duration_s + 1e-4f);
    }
  }
  out.report = pipeline.metrics()->finish();
  out.counts = pipeline.mediator().transition_counts();
  return out;
}

TEST(Transitions, TheSubject16TakesGiveAStartAndAStop) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_31_start_walk_mrl30.bvh");
  auto lib = start_stop_library();
  ASSERT_TRUE(lib.ok()) << lib.message();
  int starts = 0, stops = 0;
  for (const Transition& t : lib->transitions) {
    const bool start = t.kind == TransitionKind::kStart;
    (start ? starts : stops) += 1;
    ASSERT_GE(t.clip, 0);
    ASSERT_LT(t.clip, static_cast<int>(lib->clips.size()));
    const LocomotionClip& c = lib->clips[t.clip];
    EXPECT_TRUE(c.transition);
    EXPECT_FALSE(c.gait);  // never in the blend space
    for (const DirectionGroup& g : lib->groups) {
      EXPECT_EQ(std::count(g.clips.begin(), g.clips.end(), t.clip), 0);
    }
    EXPECT_NE(t.clip, lib->idle);
    EXPECT_NEAR(t.duration_s, c.clip.duration_s(), 1e-4f);
    EXPECT_EQ(t.speed_m_s.size(), static_cast<size_t>(c.clip.num_frames));
    // The speed profile goes from rest to a walk (start) or from a walk to rest (stop).
    const float rest = t.speed_m_s[start ? 0 : t.speed_m_s.size() - 1];
    EXPECT_LT(rest, 0.3f) << c.clip.name;
    EXPECT_GT(t.moving_speed_m_s, 0.8f) << c.clip.name;
    EXPECT_LT(t.moving_from_s, t.moving_to_s);
    // It joins a forward cycle at a phase in [0, 1).
    ASSERT_GE(t.cycle_clip, 0);
    EXPECT_TRUE(lib->clips[t.cycle_clip].gait);
    EXPECT_GE(t.cycle_phase, 0.0f);
    EXPECT_LT(t.cycle_phase, 1.0f);
    EXPECT_TRUE(t.lead_foot == 0 || t.lead_foot == 1);
    // Its feet have contacts to lock on.
    EXPECT_GT(std::count(c.plant[0].begin(), c.plant[0].end(), 1), 0);
    EXPECT_GT(std::count(c.plant[1].begin(), c.plant[1].end(), 1), 0);
  }
  EXPECT_GE(starts, 1);
  EXPECT_GE(stops, 1);
}

// The jog's sudden stop: its feet are pinned, as a gait clip's are, only where the ball rests over
// the ground as a walker's does (LocomotionLibrary::max_rest_speed_m_s), not at half the jog's
// speed, while it is still landing; every contact keeps frames to pin on.
TEST(Transitions, ASuddenStopFromAJogPinsOnlyResting) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_57_run_jog_sudden_stop_mrl30.bvh");
  auto lib = test::load_data_library({"clips/bvh/more/cmu_16_15_walk_mrl30.bvh",
                                      "clips/bvh/more/cmu_16_36_run_jog_mrl30.bvh",
                                      "clips/bvh/more/cmu_16_57_run_jog_sudden_stop_mrl30.bvh"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  ASSERT_GT(lib->max_rest_speed_m_s, 0.0f);
  int stops = 0, pinned = 0;
  for (const Transition& t : lib->transitions) {
    if (t.kind != TransitionKind::kStop) continue;
    ++stops;
    const LocomotionClip& c = lib->clips[t.clip];
    for (int s = 0; s < 2; ++s) {
      ASSERT_EQ(c.toe_speed_m_s[s].size(), c.plant[s].size());
      for (size_t f = 0; f < c.plant[s].size(); ++f) {
        if (!c.plant[s][f]) continue;
        ++pinned;
        EXPECT_LE(c.toe_speed_m_s[s][f], lib->max_rest_speed_m_s) << c.clip.name << " " << f;
      }
    }
  }
  EXPECT_GE(stops, 1);
  EXPECT_GT(pinned, 0);
}

// Each stop comes with its mirror image: the same stop ending on the other foot, so its first
// landing is half a cycle of the gait away from the stop's own.
TEST(Transitions, EveryStopHasAMirrorImageEndingOnTheOtherFoot) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_33_slow_walk_stop_mrl30.bvh");
  auto lib = start_stop_library();
  ASSERT_TRUE(lib.ok()) << lib.message();
  std::vector<const Transition*> stops;
  for (const Transition& t : lib->transitions) {
    if (t.kind == TransitionKind::kStop) stops.push_back(&t);
  }
  ASSERT_EQ(stops.size(), 2u);
  const Transition& a = *stops[0];
  const Transition& b = *stops[1];
  EXPECT_NEAR(a.moving_speed_m_s, b.moving_speed_m_s, 0.01f * a.moving_speed_m_s);
  EXPECT_NEAR(a.duration_s, b.duration_s, 1e-4f);
  EXPECT_EQ(a.lead_foot, 1 - b.lead_foot);
  EXPECT_EQ(a.cycle_clip, b.cycle_clip);
  float apart = std::abs(a.cycle_phase - b.cycle_phase);
  apart = std::min(apart, 1.0f - apart);
  EXPECT_NEAR(apart, 0.5f, 0.1f);
}

// Whatever foot an agent happens to be on when it starts slowing down (its start phase comes from
// the seed), it comes to rest in a stop clip: one of the two begins within about a step.
TEST(Transitions, AnAgentComesToRestInAStopOnEitherFoot) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_33_slow_walk_stop_mrl30.bvh");
  auto lib = start_stop_library();
  ASSERT_TRUE(lib.ok()) << lib.message();
  int played = 0;
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    MediatorParams params;
    params.seed = seed;
    test::ScriptedCrowd crowd({{glm::vec2(0.0f), stopping, nullptr}});
    CrowdPipeline pipeline(*lib, params, test::test_pipeline_options(1, kDt));
    for (int f = 0; f < 300; ++f) ASSERT_TRUE(pipeline.step(crowd, kDt).ok());
    const auto counts = pipeline.mediator().transition_counts();
    EXPECT_EQ(counts[kStopsSeen], 1u) << "seed " << seed;
    EXPECT_EQ(counts[kStopsPlayed], 1u) << "seed " << seed;
    played += static_cast<int>(counts[kStopsPlayed]);
    const MetricsReport r = pipeline.metrics()->finish();
    EXPECT_LE(r.feet.support_slide_cm_s, 2.0) << "seed " << seed;
    EXPECT_LE(r.root_error_cm.mean, 3.0) << "seed " << seed;
  }
  EXPECT_EQ(played, 8);
}

// Whether clip analysis has `side` in contact at clip time t (a loop's contacts may run past its
// end: t is tried a period on either side as well).
bool in_contact(const LocomotionClip& c, int side, float t) {
  const float period = c.clip.loops ? c.clip.duration_s() : 0.0f;
  for (const TimeInterval& iv : c.analysis.contacts[side]) {
    for (float shift : {0.0f, period, -period}) {
      if (iv.start_s <= t + shift && t + shift <= iv.end_s) return true;
    }
  }
  return false;
}

// While a transition plays, the gait phase follows its own steps (Transition::phase_track): the
// cycle clip, at that phase, lands each foot with the transition. A stop's steps change length
// and take another time than the cycle's, so a clock at the cycle's own rate from one landing
// drifts off them (the jog's sudden stop: 3 of its 8 later landings, mirror image included, find
// the cycle's foot in the air).
TEST(Transitions, TheCycleStepsWithTheTransitionsFeet) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_33_slow_walk_stop_mrl30.bvh");
  auto lib = test::subject16_library();
  ASSERT_TRUE(lib.ok()) << lib.message();
  ASSERT_FALSE(lib->transitions.empty());
  int landings = 0;
  for (const Transition& tr : lib->transitions) {
    const LocomotionClip& clip = lib->clips[tr.clip];
    const LocomotionClip& cycle = lib->clips[tr.cycle_clip];
    // Each landing of the transition after its first frame (its cut): the cycle at the track's
    // phase a frame later has that foot down too.
    for (int s = 0; s < 2; ++s) {
      for (const TimeInterval& iv : clip.analysis.contacts[s]) {
        if (iv.start_s < 0.5f / tr.fps) continue;
        const float t = iv.start_s + 1.0f / tr.fps;
        EXPECT_TRUE(in_contact(cycle, s, cycle.time_at_phase(tr.phase_at(t))))
            << clip.clip.name << " side " << s << " landing at " << iv.start_s << " s";
        ++landings;
      }
    }
  }
  EXPECT_GE(landings, 10);
}

// One agent's transition pass, run frame by frame on its own: its inputs (one layer at full
// weight) and the state the pass keeps.
struct OneAgentTransitions {
  OneAgentTransitions(const LocomotionLibrary& lib, const MediatorParams& params, int16_t clip,
                      float speed_m_s, bool stands)
      : crowd{lib, params, kDt, slot_of_agent, fresh},
        speed{speed_m_s},
        standing{static_cast<uint8_t>(stands ? 1 : 0)},
        layer_clip(kMaxBlendLayers, static_cast<int16_t>(lib.idle)),
        layer_weight(kMaxBlendLayers, 0.0f) {
    layer_clip[0] = clip;
    layer_weight[0] = 1.0f;
  }
  // One frame at speed v (standing as set).
  void step(float v) {
    speed[0] = v;
    transition_pass(crowd, speed, rate, standing, layer_clip, layer_weight, gait, phase, state);
    fresh[0] = 0;
  }
  const std::vector<int32_t> slot_of_agent{0};
  std::vector<uint8_t> fresh{1};
  const PassCrowd crowd;
  std::vector<float> speed, rate{1.0f}, gait{1.0f}, phase{0.0f};
  std::vector<uint8_t> standing;
  std::vector<int16_t> layer_clip;
  std::vector<float> layer_weight;
  std::vector<int16_t> index{-1};
  std::vector<TransitionStage> stage{TransitionStage::kNone};
  std::vector<float> time{0}, weight{0}, tr_rate{1}, waited{0}, min_cadence{0}, chosen{0}, lag{0},
      prev_speed{0}, prev_phase{0}, still{0}, moving{0}, peak{0};
  std::vector<uint8_t> start_due{0};
  std::vector<uint32_t> counts = std::vector<uint32_t>(kNumCounts, 0);
  const TransitionState state{index,       stage,  time,      weight,     tr_rate,    waited,
                              min_cadence, chosen, lag,       prev_speed, prev_phase, still,
                              moving,      peak,   start_due, counts};
};

// A stop once chosen waits for the gait phase its first step matches. A speed that rises for a
// frame while the agent slows down (a DetourCrowd agent's in a jam does so all the time) is not
// walking on: the stop is given up only once the agent is faster than when it was chosen.
TEST(Transitions, AChosenStopIsKeptThroughASpeedBumpBelowTheSpeedItWasChosenAt) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_33_slow_walk_stop_mrl30.bvh");
  auto lib = start_stop_library();
  ASSERT_TRUE(lib.ok()) << lib.message();
  const MediatorParams params;
  // The gait phase stands still: the stop's own phase never comes, so it waits.
  OneAgentTransitions t(*lib, params, static_cast<int16_t>(lib->transitions.front().cycle_clip),
                        1.1f, false);
  auto step = [&](float v) { t.step(v); };
  const std::vector<TransitionStage>& stage = t.stage;
  float v = 1.1f;
  for (int f = 0; f < 30; ++f) step(v);  // walking
  for (int f = 0; f < 60 && stage[0] != TransitionStage::kWaiting; ++f) step(v -= 1.0f * kDt);
  ASSERT_EQ(stage[0], TransitionStage::kWaiting) << "no stop chosen when slowing at 1 m/s^2";
  const float chosen_at = v;
  for (int f = 0; f < 3; ++f) step(v -= 1.0f * kDt);
  step(v += 0.6f * kDt);  // a frame's rise, still below the speed the stop was chosen at
  EXPECT_EQ(stage[0], TransitionStage::kWaiting) << "given up for a frame's rise of the speed";
  step(v = chosen_at + 0.05f);  // walking on, faster than it was
  EXPECT_EQ(stage[0], TransitionStage::kNone) << "kept though the agent walks on";
}

// A stop is an agent coming to rest from a walk. One that only crept (never as fast as a take's
// standing speed, 0.15 m/s, below every moving frame of a stop clip) has no step to stop: its rest
// is counted apart, as a creep's, and is not a stop seen and missed.
TEST(Transitions, ARestFromACreepIsNotAStop) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_33_slow_walk_stop_mrl30.bvh");
  auto lib = start_stop_library();
  ASSERT_TRUE(lib.ok()) << lib.message();
  const MediatorParams params;
  const float still = SegmentationThresholds{}.idle_speed_m_s;
  ASSERT_LT(params.stop_speed_m_s, still);
  for (const Transition& tr : lib->transitions) {
    if (tr.kind != TransitionKind::kStop) continue;
    EXPECT_GE(tr.speed_at(tr.moving_to_s - 0.5f / tr.fps), 0.9f * still);
  }
  OneAgentTransitions t(*lib, params, static_cast<int16_t>(lib->idle), 0.0f, true);
  auto step = [&](float v) {
    t.standing[0] = v < params.stop_speed_m_s ? 1 : 0;
    t.step(v);
  };
  const std::vector<uint32_t>& counts = t.counts;
  for (int f = 0; f < 30; ++f) step(0.0f);
  for (int f = 0; f < 60; ++f) step(0.9f * still);  // a creep, 1 s
  for (int f = 0; f < 30; ++f) step(0.0f);
  EXPECT_EQ(counts[kStopsSeen], 0u);
  EXPECT_EQ(counts[kCreepStops], 1u);
  for (int f = 0; f < 60; ++f) step(f < 30 ? 1.1f * still : 0.9f * still);  // faster, then slower
  for (int f = 0; f < 30; ++f) step(0.0f);
  EXPECT_EQ(counts[kStopsSeen], 1u);
  EXPECT_EQ(counts[kCreepStops], 1u);
  EXPECT_EQ(counts[kStartsSeen], 2u);
}

TEST(Transitions, TheBuiltinLibraryHasNone) {
  EXPECT_TRUE(test::builtin_library().transitions.empty());
  for (const LocomotionClip& c : test::builtin_library().clips) EXPECT_FALSE(c.transition);
}

// One transition of `kind` (0 start, 1 stop) was seen and played, for more than 20 frames and up to
// full weight, and none of the other kind; the motion stayed within the bounds.
constexpr int kStart = 0, kStop = 1;
void expect_one_played(const Played& p, int kind) {
  const int seen = kind == kStart ? kStartsSeen : kStopsSeen;
  const int played = kind == kStart ? kStartsPlayed : kStopsPlayed;
  const int other_seen = kind == kStart ? kStopsSeen : kStartsSeen;
  EXPECT_EQ(p.counts[seen], 1u);
  EXPECT_EQ(p.counts[played], 1u);
  EXPECT_EQ(p.counts[other_seen], 0u);
  EXPECT_GT(p.frames_with[kind], 20);
  EXPECT_FLOAT_EQ(p.max_weight[kind], 1.0f);
  EXPECT_EQ(p.frames_with[1 - kind], 0);
  EXPECT_LE(p.report.root_error_cm.mean, 3.0);
  EXPECT_LE(p.report.feet.support_slide_cm_s, 2.0);
  EXPECT_EQ(p.report.playback_outside_limits, 0.0);
  EXPECT_EQ(p.pops, 0);
}

TEST(Transitions, AnAgentStartingFromRestPlaysTheStartClip) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_31_start_walk_mrl30.bvh");
  auto lib = start_stop_library();
  ASSERT_TRUE(lib.ok()) << lib.message();
  expect_one_played(play(*lib, starting, 300), kStart);
}

TEST(Transitions, AnAgentComingToRestPlaysTheStopClip) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_33_slow_walk_stop_mrl30.bvh");
  auto lib = start_stop_library();
  ASSERT_TRUE(lib.ok()) << lib.message();
  expect_one_played(play(*lib, stopping, 300), kStop);
}

// An agent that sets off again while the stop it played still fades out plays the start once the
// stop has gone (it was left out: a start was played only when no stop played).
TEST(Transitions, AStartSeenAsAStopFadesOutIsPlayedAfterIt) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_33_slow_walk_stop_mrl30.bvh");
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_31_start_walk_mrl30.bvh");
  auto lib = start_stop_library();
  ASSERT_TRUE(lib.ok()) << lib.message();
  const Played p = play(*lib, stop_and_go, 420);
  EXPECT_EQ(p.counts[kStopsSeen], 1u);
  EXPECT_EQ(p.counts[kStopsPlayed], 1u);
  EXPECT_EQ(p.counts[kStartsSeen], 1u);
  EXPECT_EQ(p.counts[kStartsPlayed], 1u);
  EXPECT_GT(p.frames_with[kStart], 20);
  EXPECT_FLOAT_EQ(p.max_weight[kStart], 1.0f);
  EXPECT_LE(p.report.root_error_cm.mean, 3.0);
  EXPECT_LE(p.report.feet.support_slide_cm_s, 2.0);
  EXPECT_EQ(p.report.playback_outside_limits, 0.0);
  EXPECT_EQ(p.pops, 0);
}

// The same library with its transitions taken away: starts and stops are counted, none is played,
// no transition clip ever gets weight, and the plans are those of the blend alone.
TEST(Transitions, WithoutTransitionsNothingIsPlayed) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_33_slow_walk_stop_mrl30.bvh");
  auto lib = start_stop_library();
  ASSERT_TRUE(lib.ok()) << lib.message();
  LocomotionLibrary bare = *lib;
  bare.transitions.clear();
  for (auto velocity : {starting, stopping}) {
    const Played p = play(bare, velocity, 300);
    EXPECT_EQ(p.counts[kStartsSeen] + p.counts[kStopsSeen], 1u);
    EXPECT_EQ(p.counts[kStartsPlayed] + p.counts[kStopsPlayed], 0u);
    EXPECT_EQ(p.frames_with[0] + p.frames_with[1], 0);
    EXPECT_LE(p.report.root_error_cm.mean, 3.0);
  }
}

}  // namespace
}  // namespace gk
