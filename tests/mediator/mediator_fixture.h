#pragma once
// Runs a scripted crowd through CrowdPipeline (mediator, feedback, pose synthesis) and returns the
// METRICS.md report.

#include <cmath>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

#include "animation/clip_library.h"
#include "animation/procedural.h"
#include "mediator/mediator.h"
#include "mediator/metrics.h"
#include "mediator/pose_synthesis.h"
#include "pipeline/crowd_pipeline.h"
#include "tests/mediator/scripted_crowd.h"
#include "tests/test_data.h"

namespace gk::test {

inline const LocomotionLibrary& builtin_library() {
  static const LocomotionLibrary lib = [] {
    std::vector<ClipSet> sets{make_builtin_clip_set()};
    Result<LocomotionLibrary> r = build_locomotion_library(sets);
    if (!r.ok()) throw std::runtime_error(r.message());
    return std::move(*r);
  }();
  return lib;
}

// The built-in set without the clips whose names contain any of `drop` (e.g. {"strafe",
// "backward"} leaves forward clips only, like the mannequin and CMU sets).
inline LocomotionLibrary builtin_library_without(std::initializer_list<const char*> drop) {
  ClipSet set = make_builtin_clip_set();
  std::erase_if(set.clips, [&](const Clip& c) {
    for (const char* d : drop) {
      if (c.name.find(d) != std::string::npos) return true;
    }
    return false;
  });
  std::vector<ClipSet> sets{std::move(set)};
  Result<LocomotionLibrary> r = build_locomotion_library(sets);
  if (!r.ok()) throw std::runtime_error(r.message());
  return std::move(*r);
}

// One clip set per file of the shared data (paths relative to it), in order.
inline Result<std::vector<ClipSet>> load_data_clip_sets(std::initializer_list<const char*> files) {
  std::vector<ClipSet> sets;
  for (const char* f : files) {
    Result<ClipSet> set = load_clip_file(data_path(f));
    if (!set.ok()) return set.status();
    sets.push_back(std::move(*set));
  }
  return sets;
}

// The clip library of those files.
inline Result<LocomotionLibrary> load_data_library(std::initializer_list<const char*> files) {
  Result<std::vector<ClipSet>> sets = load_data_clip_sets(files);
  if (!sets.ok()) return sets.status();
  return build_locomotion_library(*sets);
}

// The whole CMU subject-16 set of ../shared/data/clips/bvh/more (walks, a turn, a fast walk, a
// start, a stop, a jog and a sudden stop), as one library.
inline Result<LocomotionLibrary> subject16_library() {
  return load_data_library({"clips/bvh/more/cmu_16_11_walk_veer_left.bvh",
                            "clips/bvh/more/cmu_16_15_walk_mrl30.bvh",
                            "clips/bvh/more/cmu_16_17_walk_90_left_turn_mrl30.bvh",
                            "clips/bvh/more/cmu_16_22_fast_walk_mrl30.bvh",
                            "clips/bvh/more/cmu_16_31_start_walk_mrl30.bvh",
                            "clips/bvh/more/cmu_16_33_slow_walk_stop_mrl30.bvh",
                            "clips/bvh/more/cmu_16_36_run_jog_mrl30.bvh",
                            "clips/bvh/more/cmu_16_57_run_jog_sudden_stop_mrl30.bvh"});
}

// A headless pipeline that records the metrics (by default no palettes: nothing is drawn).
inline PipelineOptions test_pipeline_options(size_t capacity, float frame_time_s,
                                             bool make_palettes = false,
                                             bool record_metrics = true) {
  PipelineOptions o;
  o.capacity = capacity;
  o.make_palettes = make_palettes;
  o.record_metrics = record_metrics;
  o.frame_time_s = frame_time_s;
  return o;
}

struct RunResult {
  MetricsReport report;
  uint64_t sanitised = 0;
  int feedback_frames = 0;
};

inline RunResult run_scripted(const LocomotionLibrary& lib, std::vector<Script> scripts,
                              MediatorParams params, int frames = 600, bool honour = false) {
  constexpr float kDt = 1.0f / 60.0f;
  ScriptedCrowd crowd(std::move(scripts), honour);
  CrowdPipeline pipeline(lib, params, test_pipeline_options(crowd.capacity(), kDt));
  RunResult out;
  for (int f = 0; f < frames; ++f) {
    const Status s = pipeline.step(crowd, kDt);
    EXPECT_TRUE(s.ok()) << s.message();
    out.feedback_frames += crowd.last_feedback_count() > 0;
  }
  out.report = pipeline.metrics()->finish();
  out.sanitised = pipeline.mediator().num_sanitised();
  return out;
}

// n agents in a row 1.5 m apart along x (ids 1..n), at rest and facing +z: the arrays a test feeds
// the mediator frame by frame, moving the agents itself.
struct AgentRow {
  std::vector<uint32_t> ids;
  std::vector<glm::vec2> p, v;
  std::vector<float> th;
  explicit AgentRow(int n) : ids(n), p(n), v(n), th(n, 0.0f) {
    for (int i = 0; i < n; ++i) {
      ids[i] = static_cast<uint32_t>(i + 1);
      p[i] = glm::vec2(1.5f * static_cast<float>(i), 0.0f);
    }
  }
  AgentFrame frame() const { return AgentFrame{ids, p, v, th}; }
};

// Pedestrians creeping and walking slowly in a row (0.1-0.6 m/s, speeding up and slowing down,
// each on its own phase), planned and posed for `seconds` at 60 Hz; after the first second
// (settling in) `on_frame(mediator, poses)` sees each frame. False if a plan failed.
template <typename OnFrame>
bool creep_row(const LocomotionLibrary& lib, int agents, float seconds, OnFrame on_frame) {
  constexpr float kDt = 1.0f / 60.0f;
  const MediatorParams params;
  Mediator m(lib, params, agents);
  PoseSynthesizer ps(lib, agents, false);
  AgentRow row(agents);
  for (int f = 0; f < static_cast<int>(seconds / kDt); ++f) {
    for (int i = 0; i < agents; ++i) {
      const float t = static_cast<float>(f) * kDt;
      const float speed = 0.1f + 0.25f * (1.0f + std::sin(0.8f * t + static_cast<float>(i)));
      row.v[i] = glm::vec2(0.0f, speed);
      row.p[i] += row.v[i] * kDt;
    }
    if (!m.plan(row.frame(), kDt).ok()) return false;
    ps.run(m.plans(), agents, m.params(), kDt);
    if (f >= static_cast<int>(1.0f / kDt)) on_frame(static_cast<const Mediator&>(m), ps);
  }
  return true;
}

inline Script straight(glm::vec2 start, glm::vec2 velocity) {
  return {start, [velocity](double) { return velocity; }, nullptr};
}

}  // namespace gk::test
