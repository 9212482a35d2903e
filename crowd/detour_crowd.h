#pragma once
// A second, existing simulator behind CrowdSource: recastnavigation's DetourCrowd, on a navmesh
// built (Recast) from the scenario's walls, so any scenario runs on either simulator.

#include <cstdint>
#include <memory>

#include "crowd/crowd_source.h"
#include "crowd/scenario.h"

namespace gk {

struct DetourParams {
  float cell_size_m = 0.1f;  // navmesh voxel size [m] [> 0]
  float max_accel_m_s2 = 8.0f;
  uint64_t seed = 1;
};

Result<std::unique_ptr<CrowdSource>> make_detour_crowd(const Scenario& scenario,
                                                       const ScenarioAgents& agents,
                                                       const DetourParams& params = {});

}  // namespace gk
