// Mediator planning and pose synthesis (sample, blend, FK, torso twist, foot IK; skinning
// palettes are the upload's, CrowdPipeline::update_palettes, not measured here), microseconds per
// agent per frame at 1,000 agents, single thread, for three skeletons: the built-in humanoid (25
// joints), the CMU walk + run (31) and the Quaternius mannequin (53). The crowd is the plaza
// scenario on social forces, stepped for two seconds first. The frame is CrowdPipeline's; each
// iteration runs a whole frame and reports one stage's time (manual time).
#include <cstdlib>
#include <string>

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include "animation/clip_library.h"
#include "animation/procedural.h"
#include "bench/plaza_crowd.h"
#include "pipeline/crowd_pipeline.h"

namespace {

constexpr float kDt = 1.0f / 60.0f;

std::string data_dir() {
  const char* env = std::getenv("GAITKEEPER_DATA");
  return env && *env ? env : GK_DEFAULT_DATA_DIR;
}

// 0: built-in, 1: CMU walk + run, 2: mannequin glb.
gk::Result<gk::LocomotionLibrary> library(int which) {
  std::vector<gk::ClipSet> sets;
  if (which == 0) {
    sets.push_back(gk::make_builtin_clip_set());
  } else {
    const std::vector<std::string> files =
        which == 1 ? std::vector<std::string>{"clips/bvh/cmu_07_01_walk.bvh",
                                              "clips/bvh/cmu_09_11_run.bvh"}
                   : std::vector<std::string>{"clips/gltf/ual_mannequin_quaternius.glb"};
    for (const std::string& f : files) {
      auto set = gk::load_clip_file(data_dir() + "/" + f);
      if (!set.ok()) return set.status();
      sets.push_back(std::move(*set));
    }
  }
  return gk::build_locomotion_library(sets);
}

void BM_MediatorAndPose(benchmark::State& state) {
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const int n = 1000;
  auto lib = library(static_cast<int>(state.range(0)));
  if (!lib.ok()) {
    state.SkipWithError(lib.message().c_str());
    return;
  }
  auto sim = gk::bench::make_plaza_crowd(n, 1);
  if (!sim.ok()) {
    state.SkipWithError(sim.message().c_str());
    return;
  }
  gk::CrowdSource& crowd = **sim;
  gk::PipelineOptions options;
  options.capacity = crowd.capacity();
  options.make_palettes = true;
  gk::CrowdPipeline pipeline(*lib, gk::MediatorParams{}, options);
  for (int i = 0; i < 120; ++i) {
    if (gk::Status s = pipeline.step(crowd, kDt); !s.ok()) {
      state.SkipWithError(s.message().c_str());
      return;
    }
  }
  const bool pose_only = state.range(1) == 1;
  for (auto _ : state) {
    if (gk::Status s = pipeline.step(crowd, kDt); !s.ok()) {
      state.SkipWithError(s.message().c_str());
      return;
    }
    // The mediator stage is plan + snapshot + feedback (the feedback was not timed before: a
    // copy of the frame and a pass of the simulator over its agents).
    const gk::PipelineTimes& t = pipeline.times();
    state.SetIterationTime(1e-3 * (pose_only ? t.pose_ms : t.mediator_ms));
  }
  state.counters["joints"] = lib->skeleton->num_joints();
  state.counters["sec_per_agent"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * n,
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert, benchmark::Counter::kIs1000);
  state.SetLabel(std::string(state.range(1) == 1 ? "pose" : "mediator") + ", " +
                 (state.range(0) == 0   ? "built-in"
                  : state.range(0) == 1 ? "CMU"
                                        : "mannequin"));
}

}  // namespace

BENCHMARK(BM_MediatorAndPose)
    ->ArgsProduct({{0, 1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime();

BENCHMARK_MAIN();
