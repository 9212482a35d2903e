#pragma once
// A second, existing simulator behind CrowdSource: recastnavigation's DetourCrowd, on a navmesh
// built (Recast) from the scenario's walls, so any scenario runs on either simulator.
//
// Navmesh: the ground rectangle bounds_min..bounds_max minus every wall (a 0.2 m thick, 2 m tall
// box around the segment) minus a margin of the largest agent radius, so agent centres on the mesh
// keep their bodies clear of walls and bounds. Agents: id i = index i of ScenarioAgents, all live
// from the start; max speed = desired speed; they walk their waypoint chain (next waypoint within
// 1 m of the current one, wrapping round when loop_waypoints), and stop at the last one otherwise.
// A start within 1 m of the walkable area is snapped onto it, farther is an error naming the agent;
// waypoints snap within 2 m. theta is the smoothed heading of the velocity, held below 0.1 m/s.
// Feedback is honoured: positions slide along the navmesh to the requested point (never through a
// wall), velocities replace Detour's and thetas ours. Deterministic: same inputs, same frames.

#include <cstdint>
#include <memory>

#include "crowd/crowd_source.h"
#include "crowd/scenario.h"

namespace gk {

struct DetourParams {
  float cell_size_m = 0.1f;     // navmesh voxel size [m] [> 0]; at most 8 million cells
  float max_accel_m_s2 = 8.0f;  // Detour's acceleration limit per agent [m/s^2] [> 0]
  // Velocity-obstacle sampling: 0 low, 1 medium, 2 good, 3 high [Limit: 0..3]. More candidate
  // velocities per agent: smoother avoidance, higher cost per step.
  int avoidance_quality = 3;
  // An agent moves at most this many times its maximum speed in an update, collision pushes
  // included (<= 0: as Detour moves it; a jam's push can otherwise move it 20 cm in a step).
  float max_step_speed_factor = 2.0f;
  uint64_t seed = 1;  // unused: DetourCrowd has no randomness
};

Result<std::unique_ptr<CrowdSource>> make_detour_crowd(const Scenario& scenario,
                                                       const ScenarioAgents& agents,
                                                       const DetourParams& params = {});

}  // namespace gk
