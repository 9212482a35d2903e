#pragma once
// The benchmarks' crowd: the plaza scenario (an open square, random goals) scaled so n agents keep
// its moderate density, on social forces.

#include <memory>

#include "crowd/scenario.h"
#include "crowd/social_forces.h"

namespace gk::bench {

inline Result<std::unique_ptr<SocialForces>> make_plaza_crowd(int n, int threads) {
  Result<Scenario> loaded = load_scenario_by_name("plaza", scenario_dir());
  if (!loaded.ok()) return loaded.status();
  const Scenario scenario = scale_scenario(*loaded, n);
  Result<ScenarioAgents> agents = expand_agents(scenario, n, 1);
  if (!agents.ok()) return agents.status();
  SocialForceParams params;
  params.threads = threads;
  return SocialForces::create(scenario, *agents, params);
}

}  // namespace gk::bench
