#pragma once
// Private to crowd/: builds a single-tile Detour navmesh (Recast) for a scenario. The ground is the
// rectangle bounds_min..bounds_max at y = 0; every wall is a box (the segment thickened sideways
// and at its ends) rasterised as a non-walkable obstacle, and the walkable area is eroded by the
// agent radius, so an agent centre on the navmesh keeps its body clear of walls and bounds.
// Detour coordinates are (x, y up, z) with our ground (x, z) at y = 0.

#include <memory>

#include "common/status.h"
#include "crowd/scenario.h"

class dtNavMesh;

namespace gk {

struct NavMeshBuildParams {
  float cell_size_m = 0.1f;       // voxel size on the ground [m] [Limit: > 0]
  float agent_radius_m = 0.3f;    // erosion of the walkable area [m] [Limit: > 0]
  float wall_thickness_m = 0.2f;  // total thickness of a wall box [m] [Limit: > 0]
  float wall_height_m = 2.0f;     // taller than the agent height: walls cannot be stepped on [m]
};

struct NavMeshDeleter {
  void operator()(dtNavMesh* navmesh) const;
};
using NavMeshPtr = std::unique_ptr<dtNavMesh, NavMeshDeleter>;

// Errors name the scenario source and the field (bounds, walls[i]) or the Recast stage that failed.
Result<NavMeshPtr> build_navmesh(const Scenario& scenario, const NavMeshBuildParams& params);

}  // namespace gk
