// Social forces step cost at 1,000, 10,000 and 100,000 agents in the plaza scenario (an open
// square with random goals, its geometry scaled so the density stays moderate: ~0.4 agents/m^2),
// on 1 and 2 threads. Target: < 1.5 us per agent per step at 10,000 agents.
#include <cstdio>

#include <benchmark/benchmark.h>

#include "bench/plaza_crowd.h"

namespace {

constexpr float kDt = 1.0f / 60.0f;

void BM_SocialForcesStep(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  auto sim = gk::bench::make_plaza_crowd(n, static_cast<int>(state.range(1)));
  if (!sim.ok()) {
    state.SkipWithError(sim.message().c_str());
    return;
  }
  // Two seconds of walking first, so agents move and meet as they do in a long run.
  for (int i = 0; i < 120; ++i) benchmark::DoNotOptimize((*sim)->step(kDt));
  for (auto _ : state) {
    const gk::Status s = (*sim)->step(kDt);
    benchmark::DoNotOptimize(s);
  }
  state.counters["agents"] = n;
  // Seconds per agent and step, printed with an SI prefix (e.g. "433ns").
  state.counters["sec_per_agent_step"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * n,
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert, benchmark::Counter::kIs1000);
}
BENCHMARK(BM_SocialForcesStep)
    ->ArgNames({"agents", "threads"})
    ->Args({1000, 1})
    ->Args({10000, 1})
    ->Args({10000, 2})
    ->Args({100000, 1})
    ->Args({100000, 2})
    ->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
