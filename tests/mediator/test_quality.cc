// The quality bounds on a representative subset of bench/quality.sh, small enough for CI:
// real crowd sources (social forces on shipped scenarios, a replayed real trajectory file) through
// the mediator and pose synthesis, measured with the METRICS.md definitions.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "animation/clip_library.h"
#include "crowd/detour_crowd.h"
#include "crowd/scenario.h"
#include "crowd/social_forces.h"
#include "crowd/trajectory_replay.h"
#include "mediator/mediator_passes.h"
#include "tests/mediator/mediator_fixture.h"
#include "tests/test_data.h"

namespace gk {
namespace {

constexpr float kDt = 1.0f / 60.0f;
constexpr int kFrames = 600;

MetricsReport run_source(CrowdSource& crowd, const LocomotionLibrary& lib, MediatorMode mode,
                         MediatorParams params = {}) {
  params.mode = mode;
  CrowdPipeline pipeline(lib, params, test::test_pipeline_options(crowd.capacity(), kDt));
  for (int f = 0; f < kFrames; ++f) {
    const Status s = pipeline.step(crowd, kDt);
    EXPECT_TRUE(s.ok()) << s.message();
  }
  return pipeline.metrics()->finish();
}

std::unique_ptr<CrowdSource> scenario_crowd(const std::string& name, bool detour = false,
                                            uint64_t seed = 1) {
  auto loaded = load_scenario_by_name(name, scenario_dir());
  EXPECT_TRUE(loaded.ok()) << loaded.message();
  const int n = loaded->default_agents;
  const Scenario s = scale_scenario(*loaded, n);
  auto agents = expand_agents(s, n, seed);
  EXPECT_TRUE(agents.ok()) << agents.message();
  if (detour) {
    auto crowd = make_detour_crowd(s, *agents);
    EXPECT_TRUE(crowd.ok()) << crowd.message();
    return std::move(*crowd);
  }
  auto sim = SocialForces::create(s, *agents, SocialForceParams{});
  EXPECT_TRUE(sim.ok()) << sim.message();
  return std::move(*sim);
}

// The mediator issue's bounds that are not about the feet: torsion limit, rate limits, heading,
// consistency with the simulator.
void expect_body_bounds(const MetricsReport& apm, bool replay, const std::string& what) {
  const MediatorParams defaults;
  EXPECT_LE(apm.torsion_deg.max, defaults.torsion_limit_deg + 0.5) << what;
  EXPECT_EQ(apm.playback_outside_limits, 0.0) << what;
  EXPECT_LE(apm.heading_error_deg.p95, 15.0) << what;
  EXPECT_LE(apm.root_error_cm.mean, replay ? 4.0 : 3.0) << what;
  if (!replay) {
    EXPECT_LE(apm.root_error_cm.max, 10.0) << what;
  }
}

// METRICS.md v2, the feet against the floor the clips were authored on: what holds everywhere
// the issue asks, and what holds on every case of this file (no foot below the floor, the naive
// crowd skating at least ten times as much on the support foot).
void expect_feet_never_below_the_floor(const MetricsReport& apm, const MetricsReport& naive,
                                       const std::string& what) {
  EXPECT_LE(apm.feet.penetration_p99_cm, 0.5) << what;
  EXPECT_LE(apm.feet.penetration_max_cm, 1.5) << what;
  EXPECT_GT(apm.feet.support_samples, 1000) << what;
  EXPECT_GE(naive.feet.support_slide_cm_s, 10.0 * apm.feet.support_slide_cm_s) << what;
}

void expect_feet_bounds(const MetricsReport& apm, const MetricsReport& naive,
                        const std::string& what) {
  expect_feet_never_below_the_floor(apm, naive, what);
  EXPECT_LE(apm.feet.support_slide_cm_s, 2.0) << what;
  EXPECT_LE(apm.feet.support_skate_ratio, 0.005) << what;
  EXPECT_LE(apm.feet.float_ratio, 0.01) << what;
  EXPECT_LE(apm.feet.limb_pop_rate, 1.0) << what;
  EXPECT_EQ(apm.pop_count, 0) << what;
}

TEST(Quality, CorridorOnSocialForcesWithBuiltinClips) {
  const LocomotionLibrary& lib = test::builtin_library();
  auto a = scenario_crowd("corridor");
  auto b = scenario_crowd("corridor");
  const MetricsReport apm = run_source(*a, lib, MediatorMode::kApm);
  expect_body_bounds(apm, false, "corridor");
  expect_feet_bounds(apm, run_source(*b, lib, MediatorMode::kNaive), "corridor");
  // The literature's foot skating: no more than 0.002 above the clips' own.
  EXPECT_LE(apm.feet.gmd_skate_ratio, apm.feet_floor.gmd_skate_ratio + 0.002);
}

TEST(Quality, GalleryUpperBodyFacesTheExhibits) {
  const LocomotionLibrary& lib = test::builtin_library();
  auto a = scenario_crowd("gallery");
  auto b = scenario_crowd("gallery");
  const MetricsReport apm = run_source(*a, lib, MediatorMode::kApm);
  expect_body_bounds(apm, false, "gallery");
  expect_feet_bounds(apm, run_source(*b, lib, MediatorMode::kNaive), "gallery");
  ASSERT_GT(apm.facing_error_within_limit_deg.count, 1000u);
  EXPECT_LE(apm.facing_error_within_limit_deg.p95, 10.0);
}

// The hardest simulated case: a jam in DetourCrowd (velocities that flip sideways from frame to
// frame) animated with a library of just two clips by different actors (CMU walk and run). Not
// yet always within the support skate and limb-pop bounds (bench/quality.md has the
// figures); what holds: the body bounds, no foot below the floor, the support slide bound, and
// far fewer limb snaps than naive's.
TEST(Quality, BottleneckJamOnDetourWithTheTwoCmuClips) {
  GK_REQUIRE_DATA("clips/bvh/cmu_07_01_walk.bvh");
  GK_REQUIRE_DATA("clips/bvh/cmu_09_11_run.bvh");
  auto lib =
      test::load_data_library({"clips/bvh/cmu_07_01_walk.bvh", "clips/bvh/cmu_09_11_run.bvh"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  auto a = scenario_crowd("bottleneck", true);
  auto b = scenario_crowd("bottleneck", true);
  const MetricsReport apm = run_source(*a, *lib, MediatorMode::kApm);
  const MetricsReport naive = run_source(*b, *lib, MediatorMode::kNaive);
  expect_body_bounds(apm, false, "bottleneck detour cmu");
  expect_feet_never_below_the_floor(apm, naive, "bottleneck detour cmu");
  EXPECT_LE(apm.feet.support_slide_cm_s, 2.0);
  EXPECT_LE(10.0 * apm.feet.limb_pop_rate, naive.feet.limb_pop_rate);
  EXPECT_LE(apm.feet.gmd_skate_ratio, apm.feet_floor.gmd_skate_ratio + 0.002);
}

// The same jam with the mannequin's keyframed clips and the support hold on (MediatorParams::
// support_hold, off by default): within the support-foot and limb-pop bounds, and the hold keeps
// the support feet put (without it, a foot carrying the body alone is dragged or let go as the
// body lurches on: its support skate is higher). The jam is chaotic (a millimetre anywhere sends
// every agent on another path), so the skate is taken over three seeds' jams: held 0.0038 against
// unheld 0.0064 (per seed held 0.0032, 0.0048 and 0.0034; 0.0028 against 0.0060 before a creeper's
// pinned feet came to stand on the floor, when one seed alone, as this test was, went over the
// bound with a first version of that: 0.0055).
// The float the hold once kept well down too is now mostly the quickened steps' doing (the rate
// pass lands the other foot before the body leaves the support's reach), too close to compare.
TEST(Quality, JammedBodiesAreHeldByTheirSupportFoot) {
  GK_REQUIRE_DATA("clips/gltf/ual_mannequin_quaternius.glb");
  auto lib = test::load_data_library({"clips/gltf/ual_mannequin_quaternius.glb"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  MediatorParams hold;
  hold.support_hold = true;
  double held_skate = 0.0, unheld_skate = 0.0;
  constexpr int kSeeds = 3;
  for (uint64_t seed = 1; seed <= kSeeds; ++seed) {
    auto a = scenario_crowd("bottleneck", true, seed);
    const MetricsReport apm = run_source(*a, *lib, MediatorMode::kApm, hold);
    const std::string what = "bottleneck detour mannequin, seed " + std::to_string(seed);
    expect_body_bounds(apm, false, what);
    auto b = scenario_crowd("bottleneck", true, seed);
    expect_feet_never_below_the_floor(apm, run_source(*b, *lib, MediatorMode::kNaive), what);
    EXPECT_LE(apm.feet.support_slide_cm_s, 2.0) << what;
    EXPECT_LE(apm.feet.limb_pop_rate, 1.0) << what;
    EXPECT_EQ(apm.pop_count, 0) << what;
    held_skate += apm.feet.support_skate_ratio / kSeeds;
    auto c = scenario_crowd("bottleneck", true, seed);
    unheld_skate += run_source(*c, *lib, MediatorMode::kApm).feet.support_skate_ratio / kSeeds;
  }
  EXPECT_LE(held_skate, 0.005);
  EXPECT_GT(unheld_skate, held_skate);
}

// Captured clips of another kind (CMU subject 16: 30 fps, centimetres, a start, a stop, turns and
// a jog among the walks). The knees and feet of captured legs near full stretch used to snap when
// a lock let go; what holds now besides the body bounds: support slide, float and limb pops.
TEST(Quality, CorridorWithTheSubject16Clips) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_15_walk_mrl30.bvh");
  auto lib = test::subject16_library();
  ASSERT_TRUE(lib.ok()) << lib.message();
  auto a = scenario_crowd("corridor");
  auto b = scenario_crowd("corridor");
  const MetricsReport apm = run_source(*a, *lib, MediatorMode::kApm);
  const MetricsReport naive = run_source(*b, *lib, MediatorMode::kNaive);
  expect_body_bounds(apm, false, "corridor more");
  expect_feet_never_below_the_floor(apm, naive, "corridor more");
  EXPECT_LE(apm.feet.support_slide_cm_s, 2.0);
  EXPECT_LE(apm.feet.float_ratio, 0.01);
  EXPECT_LE(apm.feet.limb_pop_rate, 1.0);
  EXPECT_LE(apm.feet.gmd_skate_ratio, apm.feet_floor.gmd_skate_ratio + 0.002);
}

// A library of one stop take alone (CMU 16_33: slow walk, stop): it has no steady stride, so its
// cycle is its steadiest step and that step's mirror image, trusted with foot locks (not played as
// naive plays it). A plaza crowd at walking speed then keeps its support feet planted. Not yet
// within the bounds: limb pops, about 90 per agent-minute (the take's slow walk is played faster
// than captured, and its reference accelerations are a slow walk's; `gaitkeeper bench --scenario
// plaza --clips cmu_16_33_slow_walk_stop_mrl30.bvh` gives the figures).
TEST(Quality, PlazaWithOneStopTakeAlone) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_33_slow_walk_stop_mrl30.bvh");
  auto lib = test::load_data_library({"clips/bvh/more/cmu_16_33_slow_walk_stop_mrl30.bvh"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  ASSERT_FALSE(gait_analysis_doubtful(*lib));
  auto a = scenario_crowd("plaza");
  auto b = scenario_crowd("plaza");
  const MetricsReport apm = run_source(*a, *lib, MediatorMode::kApm);
  const MetricsReport naive = run_source(*b, *lib, MediatorMode::kNaive);
  expect_body_bounds(apm, false, "plaza 16_33");
  expect_feet_never_below_the_floor(apm, naive, "plaza 16_33");
  EXPECT_LE(apm.feet.support_slide_cm_s, 2.0);
  EXPECT_LE(apm.feet.support_skate_ratio, 0.005);
  EXPECT_LE(apm.feet.float_ratio, 0.01);
  EXPECT_LE(apm.feet.gmd_skate_ratio, apm.feet_floor.gmd_skate_ratio + 0.002);
}

TEST(Quality, ReplayedPedestriansWithTheMannequinClips) {
  GK_REQUIRE_DATA("trajectories/zara1/crowds_zara01.txt");
  GK_REQUIRE_DATA("clips/gltf/ual_mannequin_quaternius.glb");
  auto lib = test::load_data_library({"clips/gltf/ual_mannequin_quaternius.glb"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  auto a = load_trajectory_replay(test::data_path("trajectories/zara1/crowds_zara01.txt"));
  auto b = load_trajectory_replay(test::data_path("trajectories/zara1/crowds_zara01.txt"));
  ASSERT_TRUE(a.ok() && b.ok());
  const MetricsReport apm = run_source(**a, *lib, MediatorMode::kApm);
  const MetricsReport naive = run_source(**b, *lib, MediatorMode::kNaive);
  expect_body_bounds(apm, true, "zara01 mannequin");
  expect_feet_never_below_the_floor(apm, naive, "zara01 mannequin");
  EXPECT_LE(apm.feet.support_slide_cm_s, 2.0);
  // The clips lift the trailing foot while the leading one is still on its heel: it stays pinned
  // until the leading foot has rolled down (0.0087 when it was let go with the clips).
  EXPECT_LE(apm.feet.support_skate_ratio, 0.005);
  EXPECT_LE(apm.feet.float_ratio, 0.01);
  EXPECT_LE(apm.feet.limb_pop_rate, 1.0);
  EXPECT_LE(apm.feet.gmd_skate_ratio, apm.feet_floor.gmd_skate_ratio + 0.002);
  EXPECT_FALSE(apm.feedback_speed_change.has_value());  // replay ignores feedback: none is asked
}

// n agents abreast, 2 m apart, going straight ahead at `speed` [m/s].
std::vector<test::Script> abreast(int n, float speed) {
  std::vector<test::Script> s;
  for (int i = 0; i < n; ++i) s.push_back(test::straight({2.0f * i, 0.0f}, {0.0f, speed}));
  return s;
}

// The fastest walk and the slowest run among a library's forward clips (-1: none).
std::pair<int, int> fastest_walk_and_slowest_run(const LocomotionLibrary& lib) {
  int walk = -1, run = -1;
  for (int c : lib.groups[lib.forward_group].clips) {
    if (lib.clips[c].double_support) {
      walk = c;
    } else if (run < 0) {
      run = c;
    }
  }
  return {walk, run};
}

// Pedestrians of 1.6 to 2.0 m/s walk (GAIT.md: people switch to running at about 2 m/s). The
// mannequin's walk (1.05 m/s) and jog (2.58 m/s, stance under a fifth of its cycle, the toes
// swung 35 cm high) meet at 1.82 m/s; blended by speed alone the jog outweighed the walk from
// there, its contacts won, and a 1.9 m/s walker floated between strides on 30% of frames.
TEST(Quality, MannequinPedestriansBelowTheWalkRunSpeedWalk) {
  GK_REQUIRE_DATA("clips/gltf/ual_mannequin_quaternius.glb");
  auto lib = test::load_data_library({"clips/gltf/ual_mannequin_quaternius.glb"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  // Froude number 0.5 at the skeleton's hip height: the hips of a flat-footed mannequin stand
  // about 0.9 m high, so about 2.1 m/s.
  EXPECT_NEAR(lib->walk_run_speed_m_s, std::sqrt(0.5f * 9.81f * 0.9f), 0.1f);
  const auto [walk, run] = fastest_walk_and_slowest_run(*lib);  // two walks, jog, sprint
  ASSERT_GE(walk, 0);
  ASSERT_GE(run, 0);
  const MediatorParams p;
  std::vector<float> w(lib->clips.size());
  for (float v = lib->clips[walk].speed_m_s; v < lib->walk_run_speed_m_s; v += 0.05f) {
    choose_clip_weights(*lib, p, v, 0.0f, w);
    EXPECT_GE(w[walk], w[run]) << v;
  }
  for (const float speed : {1.6f, 1.8f, 2.0f}) {
    const auto apm = test::run_scripted(*lib, abreast(6, speed), p, 1200);
    // (0.54 at 2.0 m/s with the jog the heavier; what floats now is each agent's first steps)
    EXPECT_LE(apm.report.feet.float_ratio, 0.01) << speed;
    EXPECT_LE(apm.report.feet.support_slide_cm_s, 2.0) << speed;
    EXPECT_LE(apm.report.feet.limb_pop_rate, 1.0) << speed;
    // At 1.8 m/s and more the walk's long stance, stretched over the longer stride, lets the
    // trailing toe go while the leading foot is still on its heel (0.005 at 1.8, 0.010 at 2.0):
    // the library has no fast walk.
    if (speed < 1.7f) {
      EXPECT_LE(apm.report.feet.support_skate_ratio, 0.005) << speed;
    }
  }
}

// A run's clips put the ball on the ground while it still travels at half the run's speed (clip
// analysis's "still" for contact: 1.75 m/s for the CMU run), and a lock started there stopped the
// drawn foot dead from that speed as it landed, every step (120 limb pops per agent-minute for a
// runner at 3.5 m/s). A lock starts where the ball rests as a walker's does: below contact
// analysis's still speed at the walk-run speed of the legs (Froude 0.5 on the leg length).
TEST(Quality, RunnersFeetLandWithoutSnapping) {
  GK_REQUIRE_DATA("clips/bvh/cmu_07_01_walk.bvh");
  GK_REQUIRE_DATA("clips/bvh/cmu_09_11_run.bvh");
  auto lib =
      test::load_data_library({"clips/bvh/cmu_07_01_walk.bvh", "clips/bvh/cmu_09_11_run.bvh"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  const float leg = 0.5f * (lib->leg_length_m[0] + lib->leg_length_m[1]);
  EXPECT_NEAR(lib->max_rest_speed_m_s, 0.5f * std::sqrt(0.5f * 9.81f * leg), 1e-3f);
  EXPECT_LT(lib->max_rest_speed_m_s, 0.5f * lib->max_speed_m_s);  // tighter than a run's "still"
  for (const float speed : {3.0f, 3.5f}) {
    const auto apm = test::run_scripted(*lib, abreast(4, speed), MediatorParams{}, 1200);
    EXPECT_LE(apm.report.feet.limb_pop_rate, 1.0) << speed;
    EXPECT_LE(apm.report.feet.penetration_max_cm, 1.5) << speed;
  }
}

// A person walks or runs, never both at once (GAIT.md: the switch comes at about 2 m/s). The
// subject-16 fast walk (1.73 m/s) played faster and its jog (2.86 m/s) played slower both reach
// the walk-run speed: each plays alone on its side of it, and the gait changes over a band of a
// tenth of that speed. Blended by speed across the whole bracket, a 2.4 m/s runner mixed the
// walk's double support with the jog's flight: the blend planted a foot at the walk's contact
// while the jog's was still swinging forward at 2-3 m/s, and the lock stopped it dead there.
TEST(Quality, WalkersAndRunnersDoNotMixTheirGaits) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_36_run_jog_mrl30.bvh");
  auto lib = test::subject16_library();
  ASSERT_TRUE(lib.ok()) << lib.message();
  const auto [walk, run] = fastest_walk_and_slowest_run(*lib);
  ASSERT_GE(walk, 0);
  ASSERT_GE(run, 0);
  const MediatorParams p;
  const float v_walk = lib->clips[walk].speed_m_s, v_run = lib->clips[run].speed_m_s;
  // The two can meet: the walk at its fastest rate outruns the run at its slowest.
  ASSERT_LT(v_run * p.min_playback_rate, v_walk * p.max_playback_rate);
  const float centre = std::clamp(lib->walk_run_speed_m_s, v_run * p.min_playback_rate,
                                  v_walk * p.max_playback_rate);
  std::vector<float> w(lib->clips.size());
  float last_run = 0.0f;
  for (float v = v_walk; v <= v_run; v += 0.01f) {
    choose_clip_weights(*lib, p, v, 0.0f, w);
    EXPECT_NEAR(w[walk] + w[run], 1.0f, 1e-5f) << v;
    EXPECT_GE(w[run], last_run - 1e-6f) << v;  // the run's share only grows with the speed
    last_run = w[run];
    if (std::abs(v - centre) > 0.05f * centre + 1e-3f) {
      EXPECT_EQ(std::min(w[walk], w[run]), 0.0f) << v;  // one gait alone
      EXPECT_EQ(w[run] > 0.5f, v > centre) << v;
    }
  }
  for (const float speed : {1.9f, 2.4f, 2.7f}) {
    const auto apm = test::run_scripted(*lib, abreast(4, speed), p, 1200);
    EXPECT_LE(apm.report.feet.limb_pop_rate, 1.0) << speed;
    EXPECT_LE(apm.report.feet.support_slide_cm_s, 2.0) << speed;
    EXPECT_LE(apm.report.root_error_cm.mean, 3.0) << speed;
    // (Before: 6.0 cm/s and a skate ratio of 0.086 at 2.4 m/s, the fast walk weighing 0.4.)
    if (speed > centre) {
      EXPECT_LE(apm.report.feet.support_skate_ratio, 0.005) << speed;
    }
  }
}

// How far a knee lies on the pelvis's forward side of its hip-ankle line in a pose's model or
// world joints [m] (negative: behind, a knee bent backwards). Forward is across the hips, left
// to right, turned a quarter about the vertical.
float knee_ahead_m(std::span<const glm::mat4> w, const Skeleton& sk, Side sd) {
  const glm::vec3 across =
      translation_of(w[sk.hip(Side::kLeft)]) - translation_of(w[sk.hip(Side::kRight)]);
  const glm::vec3 facing = glm::normalize(glm::vec3(-across.z, 0.0f, across.x));
  const glm::vec3 hip = translation_of(w[sk.hip(sd)]), knee = translation_of(w[sk.knee(sd)]),
                  ankle = translation_of(w[sk.ankle(sd)]);
  const glm::vec3 axis = glm::normalize(ankle - hip);
  return glm::dot((knee - hip) - axis * glm::dot(knee - hip, axis), facing);
}

// Every knee of every agent on every frame of a scripted run: the worst, how far it lies on the
// pelvis's forward side of its hip-ankle line [m] (negative: behind), and how many were measured.
struct KneeCheck {
  float worst = 0.0f;
  int legs = 0;
};
KneeCheck worst_knee_behind(const LocomotionLibrary& lib, std::vector<test::Script> scripts,
                            int frames) {
  const Skeleton& sk = *lib.skeleton;
  constexpr float kDt = 1.0f / 60.0f;
  test::ScriptedCrowd crowd(std::move(scripts), false);
  CrowdPipeline pipeline(lib, MediatorParams{},
                         test::test_pipeline_options(crowd.capacity(), kDt, false, false));
  KneeCheck out;
  for (int f = 0; f < frames; ++f) {
    EXPECT_TRUE(pipeline.step(crowd, kDt).ok());
    const AnimationPlans& pl = pipeline.plans();
    for (size_t a = 0; a < pl.slot_of_agent.size(); ++a) {
      const int slot = pl.slot_of_agent[a];
      if (slot < 0) continue;
      const std::span<const glm::mat4> w = pipeline.poses().world(slot);
      for (const Side sd : {Side::kLeft, Side::kRight}) {
        out.worst = std::min(out.worst, knee_ahead_m(w, sk, sd));
        ++out.legs;
      }
    }
  }
  return out;
}

// No knee folds backwards: on every frame of every agent, each knee lies on the pelvis's forward
// side of its hip-ankle line, or at most 2 cm behind it (a knee overextended by about 6 degrees).
// The subject-16 set with the CMU pair, another skeleton retargeted onto it: the CMU run's cycle
// held its left knee 11 degrees backwards through the push-off where the loop's seam was closed
// on the stance leg, and the leg IK folded it back and forth (rush: 461 leg-frames, up to 13 cm
// behind). Runners, and walkers who speed up into a run and slow down again.
TEST(Quality, KneesNeverFoldBackwards) {
  GK_REQUIRE_DATA("clips/bvh/cmu_09_11_run.bvh");
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_36_run_jog_mrl30.bvh");
  auto lib = test::load_data_library(
      {"clips/bvh/more/cmu_16_15_walk_mrl30.bvh", "clips/bvh/more/cmu_16_22_fast_walk_mrl30.bvh",
       "clips/bvh/more/cmu_16_36_run_jog_mrl30.bvh", "clips/bvh/cmu_07_01_walk.bvh",
       "clips/bvh/cmu_09_11_run.bvh"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  std::vector<test::Script> s;
  for (int i = 0; i < 4; ++i) {
    s.push_back(test::straight({2.0f * i, 0.0f}, {0.0f, 3.0f + 0.25f * i}));
    s.push_back({{2.0f * i + 1.0f, 0.0f},
                 [i](double t) {
                   return glm::vec2(0.0f, 2.2f + 1.2f * static_cast<float>(std::sin(0.7 * t + i)));
                 },
                 nullptr});
  }
  const KneeCheck k = worst_knee_behind(*lib, std::move(s), 900);
  const float worst = k.worst;
  EXPECT_GT(k.legs, 900 * 8);
  EXPECT_GT(worst, -0.02f) << "a knee " << -worst * 100.0f << " cm behind its hip-ankle line";
}

// A capture whose knees straighten fully, and a little past it, in the stance (marker noise, a
// retarget): the leg IK, shortening such a leg, bends the knee forward, the way the clips' knees
// bend, not backwards the way the drawn knee's few millimetres of overextension point. The CMU
// walk with each knee that is straighter than 4 degrees turned 4 degrees past straight (the knee
// then lies about 1.4 cm behind its hip-ankle line), walkers slower and faster than the clip.
TEST(Quality, OverextendedCaptureKneesStillBendForward) {
  GK_REQUIRE_DATA("clips/bvh/cmu_07_01_walk.bvh");
  Result<std::vector<ClipSet>> sets = test::load_data_clip_sets({"clips/bvh/cmu_07_01_walk.bvh"});
  ASSERT_TRUE(sets.ok()) << sets.message();
  const Skeleton& sk = *(*sets)[0].skeleton;
  Clip& c = (*sets)[0].clips.at(0);
  constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;
  std::vector<glm::mat4> m(sk.num_joints());
  int turned = 0;
  for (int f = 0; f < c.num_frames; ++f) {
    clip_frame_model(c, sk, f, m);
    const glm::vec3 left = glm::normalize(translation_of(m[sk.hip(Side::kLeft)]) -
                                          translation_of(m[sk.hip(Side::kRight)]));
    for (const Side sd : {Side::kLeft, Side::kRight}) {
      const glm::vec3 hip = translation_of(m[sk.hip(sd)]), knee = translation_of(m[sk.knee(sd)]),
                      ankle = translation_of(m[sk.ankle(sd)]);
      const float bend = std::acos(std::clamp(
          glm::dot(glm::normalize(knee - hip), glm::normalize(ankle - knee)), -1.0f, 1.0f));
      if (bend > 4.0f * kDeg) continue;
      // The shin turned about the body's left-right axis through the knee, the ankle forward:
      // from `bend` forward to 4 degrees past straight (a knee bent forward has its ankle behind
      // the thigh's line).
      const glm::quat thigh = glm::normalize(glm::quat_cast(glm::mat3(m[sk.knee(sd)])) *
                                             glm::inverse(c.frame_rotations(f)[sk.knee(sd)]));
      const glm::quat turn = glm::angleAxis(-(bend + 4.0f * kDeg), left);
      glm::quat& q = c.rotations[static_cast<size_t>(f) * c.num_joints + sk.knee(sd)];
      q = glm::normalize(glm::inverse(thigh) * turn * thigh * q);
      ++turned;
    }
  }
  ASSERT_GT(turned, 10);
  // The clip itself: its knees now lie behind their lines by up to about 1.4 cm.
  float clip_worst = 0.0f;
  for (int f = 0; f < c.num_frames; ++f) {
    clip_frame_model(c, sk, f, m);
    for (const Side sd : {Side::kLeft, Side::kRight}) {
      clip_worst = std::min(clip_worst, knee_ahead_m(m, sk, sd));
    }
  }
  EXPECT_LT(clip_worst, -0.01f);
  EXPECT_GT(clip_worst, -0.02f);
  auto lib = build_locomotion_library(*sets);
  ASSERT_TRUE(lib.ok()) << lib.message();
  std::vector<test::Script> s;
  for (int i = 0; i < 6; ++i) {
    s.push_back(test::straight({2.0f * i, 0.0f}, {0.0f, 0.8f + 0.2f * i}));
  }
  const float worst = worst_knee_behind(*lib, std::move(s), 600).worst;
  EXPECT_GT(worst, -0.02f) << "a knee " << -worst * 100.0f << " cm behind its hip-ankle line";
}

// A library of one jog (the subject-16 take that ends in a sudden stop) played for walkers: below
// the walk-run speed they walk, whatever the clips, so a pinned ball does not rise with the slowed
// jog's push-off into a flight it does not have (it stayed up above the low swinging foot, which
// then slid along the floor: support slide 17.9 cm/s against naive's 87 on the plaza).
TEST(Quality, AJogPlayedForWalkersKeepsItsSupportFootDown) {
  GK_REQUIRE_DATA("clips/bvh/more/cmu_16_57_run_jog_sudden_stop_mrl30.bvh");
  auto lib = test::load_data_library({"clips/bvh/more/cmu_16_57_run_jog_sudden_stop_mrl30.bvh"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  std::vector<test::Script> s;
  for (int i = 0; i < 4; ++i) {
    s.push_back(test::straight({2.0f * i, 0.0f}, {0.0f, 1.1f + 0.1f * static_cast<float>(i)}));
  }
  ASSERT_LT(1.4f, lib->walk_run_speed_m_s);
  MediatorParams naive_p;
  naive_p.mode = MediatorMode::kNaive;
  const auto naive = test::run_scripted(*lib, s, naive_p, 600);
  const auto apm = test::run_scripted(*lib, s, MediatorParams{}, 600);
  ASSERT_GT(naive.report.feet.support_samples, 0);
  EXPECT_LE(10.0 * apm.report.feet.support_slide_cm_s, naive.report.feet.support_slide_cm_s);
}

// Pedestrians who appear mid-stride (a recorded crowd's tracks begin anywhere) stand on their
// support foot from the first frame: on the floor, pinned, and reached by the leg until the other
// foot lands, as a walker's would be. The mannequin's walk blended with its jog at 1.4-1.7 m/s
// holds a trailing toe 5-10 cm up and further back than the leg reaches: pinned there, it was let
// go at once and both feet were off the floor until the first landing (float 0.17 over these
// first half-seconds).
TEST(Quality, PedestriansAppearingMidStrideStandOnTheirSupportFoot) {
  GK_REQUIRE_DATA("clips/gltf/ual_mannequin_quaternius.glb");
  auto lib = test::load_data_library({"clips/gltf/ual_mannequin_quaternius.glb"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  std::vector<test::Script> s;
  for (int i = 0; i < 48; ++i) {  // random phases (the mediator's spawn), four speeds
    const float speed = 1.4f + 0.1f * static_cast<float>(i % 4);
    s.push_back(test::straight({2.0f * static_cast<float>(i), 0.0f}, {0.0f, speed}));
  }
  // Half a second: each agent's first landing, no steady walking after it.
  const auto apm = test::run_scripted(*lib, s, MediatorParams{}, 30);
  EXPECT_LE(apm.report.feet.float_ratio, 0.01);
  EXPECT_LE(apm.report.feet.support_slide_cm_s, 2.0);
  EXPECT_LE(apm.report.feet.support_skate_ratio, 0.005);
  EXPECT_LE(apm.report.feet.limb_pop_rate, 1.0);
  EXPECT_LE(apm.report.feet.penetration_max_cm, 0.5);
}

}  // namespace

// ETH's hotel annotations with `sigma` [m] of Gaussian noise added to every sample (0.4 s apart),
// as a detector's positions have it, in a temporary file (its path returned).
std::string noisy_copy(const std::string& file, double sigma, const std::string& name) {
  std::ifstream in(test::data_path(file));
  EXPECT_TRUE(in.good()) << file;
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream out(path);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, sigma);
  std::string line;
  int samples = 0;
  while (std::getline(in, line)) {
    std::istringstream row(line);
    double frame, id, x, y;
    if (!(row >> frame >> id >> x >> y)) continue;
    out << frame << ' ' << id << ' ' << x + noise(rng) << ' ' << y + noise(rng) << '\n';
    ++samples;
  }
  EXPECT_GT(samples, 1000) << file;
  return path;
}

// A tracker's noise moves standing people's p at walking-like speeds in a new direction every
// sample. With stand_through_jitter they stand, and the body and support-foot bounds hold; without
// it the mannequins walked and turned after each wobble (heading error p95 75 degrees against 7,
// skate 0.0060 against 0.0016).
TEST(Quality, TrackerNoiseDoesNotWalkStandingPedestrians) {
  GK_REQUIRE_DATA("trajectories/hotel/biwi_hotel.txt");
  GK_REQUIRE_DATA("clips/gltf/ual_mannequin_quaternius.glb");
  auto lib = test::load_data_library({"clips/gltf/ual_mannequin_quaternius.glb"});
  ASSERT_TRUE(lib.ok()) << lib.message();
  const std::string noisy =
      noisy_copy("trajectories/hotel/biwi_hotel.txt", 0.02, "gk_hotel_noisy.txt");
  MediatorParams off;
  off.stand_through_jitter = false;
  auto a = load_trajectory_replay(noisy);
  auto b = load_trajectory_replay(noisy);
  auto c = load_trajectory_replay(noisy);
  ASSERT_TRUE(a.ok() && b.ok() && c.ok());
  const MetricsReport apm = run_source(**a, *lib, MediatorMode::kApm);
  const MetricsReport walked = run_source(**b, *lib, MediatorMode::kApm, off);
  const MetricsReport naive = run_source(**c, *lib, MediatorMode::kNaive);
  std::filesystem::remove(noisy);
  expect_body_bounds(apm, true, "noisy hotel mannequin");
  expect_feet_never_below_the_floor(apm, naive, "noisy hotel mannequin");
  EXPECT_LE(apm.feet.support_slide_cm_s, 2.0);
  EXPECT_LE(apm.feet.support_skate_ratio, 0.005);
  EXPECT_LE(apm.feet.limb_pop_rate, 1.0);
  // Its floats are a 2.1 m/s walker's, whose noisy speed crosses the mannequin's walk-run switch
  // (0.015 here, 0.021 without the gate; open, as on biwi_eth): no worse than without.
  EXPECT_LE(apm.feet.float_ratio, walked.feet.float_ratio);
  EXPECT_LT(apm.feet.support_skate_ratio, walked.feet.support_skate_ratio);
  // Without it the lower body turned after the noise and lagged its direction by far more.
  EXPECT_GT(walked.heading_error_deg.p95, 3.0 * apm.heading_error_deg.p95);
}

// Held standing only through jitter: over whole recordings (ETH and Zara as annotated, and the
// hotel with 2 cm of noise), no pedestrian is taken to stand while its p goes more than half a
// metre from where it stopped (a hold that fed its own threshold once kept walkers standing for
// metres).
TEST(Quality, RecordedPedestriansAreNotHeldStandingWhileTheyWalkAway) {
  GK_REQUIRE_DATA("trajectories/eth/biwi_eth.txt");
  GK_REQUIRE_DATA("trajectories/zara1/crowds_zara01.txt");
  GK_REQUIRE_DATA("trajectories/hotel/biwi_hotel.txt");
  const std::string noisy =
      noisy_copy("trajectories/hotel/biwi_hotel.txt", 0.02, "gk_hotel_noisy_whole.txt");
  const std::pair<std::string, float> files[] = {
      {test::data_path("trajectories/eth/biwi_eth.txt"), 0.667f},
      {test::data_path("trajectories/zara1/crowds_zara01.txt"), 0.4f},
      {noisy, 0.4f}};
  for (const auto& [file, frame_time] : files) {
    ReplayOptions options;
    options.frame_time_s = frame_time;
    auto src = load_trajectory_replay(file, options);
    ASSERT_TRUE(src.ok()) << src.message();
    const float dt = 1.0f / 60.0f;
    CrowdPipeline pipeline(test::builtin_library(), MediatorParams{},
                           test::test_pipeline_options((*src)->capacity(), dt, false, false));
    std::map<uint32_t, glm::vec2> stood_at;
    int held_far = 0, stood = 0;
    for (int f = 0; f < 60 * 600; ++f) {  // ten minutes: every track of the three files
      ASSERT_TRUE(pipeline.step(**src, dt).ok());
      const AgentFrame fr = pipeline.frame();
      const AnimationPlans& pl = pipeline.plans();
      for (size_t i = 0; i < fr.size(); ++i) {
        const uint32_t id = fr.ids[i];
        if (!pl.standing[static_cast<size_t>(pl.slot_of_agent[i])]) {
          stood_at.erase(id);
          continue;
        }
        auto [it, fresh] = stood_at.emplace(id, fr.positions[i]);
        stood += fresh;
        held_far += glm::length(fr.positions[i] - it->second) > 0.5f;
      }
    }
    EXPECT_GT(stood, 5) << file << ": some pedestrians stood";
    EXPECT_EQ(held_far, 0) << file;
  }
  std::filesystem::remove(noisy);
}

}  // namespace gk
