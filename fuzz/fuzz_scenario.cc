// libFuzzer harness: scenario JSON through parse_scenario, and a valid scenario through
// scale_scenario and expand_agents for a few agents (spawn areas, waypoints, speeds).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "crowd/scenario.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  gk::Result<gk::Scenario> scenario = gk::parse_scenario(text, "fuzz.json");
  if (!scenario.ok()) return 0;
  // Few agents: the harness looks for crashes in the expansion, not for its speed.
  const int num_agents = std::clamp(scenario->default_agents, 0, 32);
  const gk::Scenario scaled = gk::scale_scenario(*scenario, num_agents);
  (void)gk::expand_agents(scaled, num_agents, /*seed=*/size);
  return 0;
}
