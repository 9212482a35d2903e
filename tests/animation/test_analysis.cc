// Clip analysis against numbers stated independently: PROVENANCE.md's root speeds for the CMU clips
// and METRICS.md's measured foot-slide floors; contact structure checked against gait facts.

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "animation/analysis.h"
#include "animation/clip_library.h"
#include "animation/foot_metrics.h"
#include "tests/test_data.h"

namespace gk {
namespace {

struct Loaded {
  ClipSet set;
  ClipAnalysis analysis;
};

Loaded load_and_analyze(const std::string& rel) {
  Result<ClipSet> set = load_clip_file(test::data_path(rel));
  EXPECT_TRUE(set.ok()) << set.message();
  if (!set.ok()) return {};
  Loaded out{std::move(*set), {}};
  out.analysis = analyze_clip(out.set.clips.at(0), *out.set.skeleton);
  return out;
}

// Left and right contact starts interleave: L R L R ... (or R L R L ...).
void expect_alternating(const ClipAnalysis& a) {
  struct Start {
    float t;
    int side;
  };
  std::vector<Start> starts;
  for (int s = 0; s < 2; ++s) {
    for (const TimeInterval& c : a.contacts[s]) starts.push_back({c.start_s, s});
  }
  std::sort(starts.begin(), starts.end(), [](const Start& x, const Start& y) { return x.t < y.t; });
  ASSERT_GE(starts.size(), 3u);
  for (size_t k = 1; k < starts.size(); ++k) {
    EXPECT_NE(starts[k].side, starts[k - 1].side) << a.name << " contact start " << starts[k].t;
  }
}

TEST(Analysis, CmuWalkSpeedContactsCycleAndFloor) {
  GK_REQUIRE_DATA("clips/bvh/cmu_07_01_walk.bvh");
  const Loaded l = load_and_analyze("clips/bvh/cmu_07_01_walk.bvh");
  const ClipAnalysis& a = l.analysis;
  EXPECT_NEAR(a.native_speed_m_s, 1.36f, 0.05f * 1.36f);  // PROVENANCE.md: 1.36 m/s
  EXPECT_FALSE(a.in_place);
  EXPECT_LT(std::abs(a.direction_rad), 0.1f);  // travels forward (+z, the way it faces)
  expect_alternating(a);
  // One stride at ~100-120 steps/min lasts 1.0-1.2 s (GAIT.md cadence).
  const float cycle = a.cycle.end_s - a.cycle.start_s;
  EXPECT_GT(cycle, 0.95f);
  EXPECT_LT(cycle, 1.25f);
  // Walking: stance over 40 % of the stride for each foot (METRICS-style contact is strict).
  for (int s = 0; s < 2; ++s) {
    for (const TimeInterval& c : a.contacts[s]) {
      if (c.start_s > 0.01f && c.end_s < a.duration_s - 0.01f) {
        EXPECT_GT(c.end_s - c.start_s, 0.4f * cycle);
      }
    }
  }
  // METRICS.md measured the floor of this clip at 60 Hz: 12 cm/s, skate 5 %, drift 1.6 cm.
  EXPECT_NEAR(a.floor.mean_cm_s, 12.0f, 1.2f);
  EXPECT_NEAR(a.floor.skate_ratio, 0.05f, 0.01f);
  EXPECT_NEAR(a.floor.drift_cm_per_step, 1.6f, 0.3f);
}

TEST(Analysis, CmuRunSpeedContactsCycleAndFloor) {
  GK_REQUIRE_DATA("clips/bvh/cmu_09_11_run.bvh");
  const Loaded l = load_and_analyze("clips/bvh/cmu_09_11_run.bvh");
  const ClipAnalysis& a = l.analysis;
  EXPECT_NEAR(a.native_speed_m_s, 3.50f, 0.05f * 3.50f);  // PROVENANCE.md: 3.50 m/s
  expect_alternating(a);
  // Running at 160-180 steps/min: a stride of 0.67-0.75 s; allow capture variation.
  const float cycle = a.cycle.end_s - a.cycle.start_s;
  EXPECT_GT(cycle, 0.6f);
  EXPECT_LT(cycle, 0.9f);
  // Flight phase: no instant where both feet are in contact.
  for (const TimeInterval& l : a.contacts[0]) {
    for (const TimeInterval& r : a.contacts[1]) {
      EXPECT_FALSE(l.start_s < r.end_s && r.start_s < l.end_s)
          << "double support in a run at " << l.start_s << " / " << r.start_s;
    }
  }
  // METRICS.md: 26 cm/s, skate 24 %, drift 2.3 cm.
  EXPECT_NEAR(a.floor.mean_cm_s, 26.0f, 2.6f);
  EXPECT_NEAR(a.floor.skate_ratio, 0.24f, 0.03f);
  EXPECT_NEAR(a.floor.drift_cm_per_step, 2.3f, 0.4f);
}

TEST(Analysis, InPlaceLoopsGetSpeedFromTheStanceFoot) {
  GK_REQUIRE_DATA("clips/bvh/ual_walk_loop.bvh");
  const Loaded walk = load_and_analyze("clips/bvh/ual_walk_loop.bvh");
  EXPECT_TRUE(walk.analysis.in_place);
  // PROVENANCE.md: mid-stance foot speed relative to the hips 1.04-1.13 m/s.
  EXPECT_GT(walk.analysis.native_speed_m_s, 1.0f);
  EXPECT_LT(walk.analysis.native_speed_m_s, 1.16f);
  // One stride per loop: one contact per foot, the cycle is the whole 1.333 s loop.
  EXPECT_EQ(walk.analysis.contacts[0].size(), 1u);
  EXPECT_EQ(walk.analysis.contacts[1].size(), 1u);
  EXPECT_NEAR(walk.analysis.cycle.end_s - walk.analysis.cycle.start_s, 32.0f / 24.0f, 1e-3f);

  const Loaded idle = load_and_analyze("clips/bvh/ual_idle_loop.bvh");
  EXPECT_LT(idle.analysis.native_speed_m_s, 0.01f);  // PROVENANCE.md: drift < 0.01 m/s
  for (int s = 0; s < 2; ++s) {
    ASSERT_EQ(idle.analysis.contacts[s].size(), 1u);
    const TimeInterval c = idle.analysis.contacts[s][0];
    EXPECT_GT(c.end_s - c.start_s, 0.9f * idle.analysis.duration_s);  // standing all the time
  }
}

TEST(Analysis, PhaseIsZeroAtLeftContactsAndIncreases) {
  GK_REQUIRE_DATA("clips/bvh/cmu_07_01_walk.bvh");
  const Loaded l = load_and_analyze("clips/bvh/cmu_07_01_walk.bvh");
  const ClipAnalysis& a = l.analysis;
  ASSERT_EQ(a.phase.size(), static_cast<size_t>(a.num_frames));
  // A contact already under way on the take's first frame starts no step.
  for (const TimeInterval& c : a.contacts[0]) {
    const int f = static_cast<int>(std::lround(c.start_s * a.fps));
    if (f == 0) continue;
    const float p = a.phase[f];
    EXPECT_LT(std::min(p, 1.0f - p), 0.01f) << "left contact at " << c.start_s;
  }
  for (const TimeInterval& c : a.contacts[1]) {
    const int f = static_cast<int>(std::lround(c.start_s * a.fps));
    if (f == 0) continue;
    EXPECT_NEAR(a.phase[f], 0.5f, 0.01f) << "right contact at " << c.start_s;
  }
  int backward = 0;
  for (int f = 1; f < a.num_frames; ++f) {
    const float d = a.phase[f] - a.phase[f - 1];
    if (d < 0.0f && d > -0.5f) ++backward;  // a drop of ~1 is the wrap
  }
  EXPECT_EQ(backward, 0);
}

// CMU subject 16 (clips/bvh/more: a cgspeed 120 fps take in CMU units and MRL 30 fps retargets in
// centimetres): the steady takes' speeds match the root speeds PROVENANCE.md measured
// independently (within 5%), and left and right contacts alternate (a contact already under way
// on the first frame starts no step).
TEST(Analysis, SubjectSixteenSteadyTakes) {
  struct Take {
    const char* file;
    float speed_m_s;  // PROVENANCE.md "Average root speed"
  };
  for (const Take& t : {Take{"clips/bvh/more/cmu_16_11_walk_veer_left.bvh", 0.96f},
                        Take{"clips/bvh/more/cmu_16_15_walk_mrl30.bvh", 1.17f},
                        Take{"clips/bvh/more/cmu_16_22_fast_walk_mrl30.bvh", 1.73f},
                        Take{"clips/bvh/more/cmu_16_36_run_jog_mrl30.bvh", 2.86f}}) {
    GK_REQUIRE_DATA(t.file);
    const Loaded l = load_and_analyze(t.file);
    const ClipAnalysis& a = l.analysis;
    EXPECT_NEAR(a.native_speed_m_s, t.speed_m_s, 0.05f * t.speed_m_s) << t.file;
    EXPECT_LT(std::abs(a.direction_rad), 0.1f) << t.file;  // forward, the way it faces
    struct Start {
      float t;
      int side;
    };
    std::vector<Start> starts;
    for (int s = 0; s < 2; ++s) {
      for (const TimeInterval& c : a.contacts[s]) {
        if (c.start_s > 0.5f / a.fps) starts.push_back({c.start_s, s});
      }
    }
    std::sort(starts.begin(), starts.end(),
              [](const Start& x, const Start& y) { return x.t < y.t; });
    ASSERT_GE(starts.size(), 3u) << t.file;
    for (size_t k = 1; k < starts.size(); ++k) {
      EXPECT_NE(starts[k].side, starts[k - 1].side) << t.file << " contact start " << starts[k].t;
    }
  }
}

// Every subject-16 take, steady or not, moves at PROVENANCE.md's average root speed (path length
// over 0.5 s samples / time) within 5%: a take that turns 90 degrees or stops covers more ground
// than its net displacement (16_17: 0.71 m/s net against 0.94 along its path).
TEST(Analysis, EveryTakeMovesAtItsSpeedAlongItsPath) {
  struct Take {
    const char* file;
    float speed_m_s;  // PROVENANCE.md "Average root speed"
  };
  for (const Take& t : {Take{"clips/bvh/more/cmu_16_11_walk_veer_left.bvh", 0.96f},
                        Take{"clips/bvh/more/cmu_16_15_walk_mrl30.bvh", 1.17f},
                        Take{"clips/bvh/more/cmu_16_17_walk_90_left_turn_mrl30.bvh", 0.94f},
                        Take{"clips/bvh/more/cmu_16_22_fast_walk_mrl30.bvh", 1.73f},
                        Take{"clips/bvh/more/cmu_16_31_start_walk_mrl30.bvh", 1.03f},
                        Take{"clips/bvh/more/cmu_16_33_slow_walk_stop_mrl30.bvh", 0.86f},
                        Take{"clips/bvh/more/cmu_16_36_run_jog_mrl30.bvh", 2.86f},
                        Take{"clips/bvh/more/cmu_16_57_run_jog_sudden_stop_mrl30.bvh", 1.50f}}) {
    GK_REQUIRE_DATA(t.file);
    const Loaded l = load_and_analyze(t.file);
    EXPECT_NEAR(l.analysis.native_speed_m_s, t.speed_m_s, 0.05f * t.speed_m_s) << t.file;
  }
}

TEST(FootMetrics, SlideOfAKnownTrack) {
  // A foot down for 10 frames at 60 Hz creeping 1 mm per frame along x, then lifted 10 cm:
  // slide 6 cm/s on each of the 9 contact pairs, one interval of 9 mm drift.
  std::vector<glm::vec3> toe, ankle;
  for (int f = 0; f < 20; ++f) {
    const bool down = f < 10;
    toe.push_back({0.001f * f, down ? 0.0f : 0.1f, 0.0f});
    ankle.push_back({0.001f * f, down ? 0.05f : 0.15f, 0.0f});
  }
  SlideAccumulator acc;
  acc.add_track(toe, ankle, 1.0f / 60.0f);
  const SlideStats s = acc.finish();
  EXPECT_EQ(s.num_samples, 9);
  EXPECT_NEAR(s.mean_cm_s, 6.0f, 1e-3f);
  EXPECT_NEAR(s.drift_cm_per_step, 0.9f, 1e-4f);
  EXPECT_EQ(s.skate_ratio, 0.0f);
}

}  // namespace
}  // namespace gk
