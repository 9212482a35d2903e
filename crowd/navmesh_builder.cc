#include "crowd/navmesh_builder.h"

#include <cmath>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include <DetourAlloc.h>
#include <DetourNavMesh.h>
#include <DetourNavMeshBuilder.h>
#include <Recast.h>

namespace gk {
namespace {

// Recast keeps a pointer per cell plus the spans: bound the grid so a huge scenario or a tiny cell
// size fails with a message instead of exhausting memory. Poly mesh vertices are 16-bit voxels.
constexpr double kMaxCells = 8.0e6;
constexpr int kMaxCellsPerAxis = 32000;
constexpr float kCellHeight_m = 0.1f;
constexpr float kAgentHeight_m = 1.8f;
constexpr float kAgentClimb_m = 0.3f;
constexpr float kWalkableSlope_deg = 45.0f;
constexpr unsigned short kWalkableFlag = 1;  // the default dtQueryFilter needs a non-zero flag

struct HeightfieldDeleter {
  void operator()(rcHeightfield* p) const { rcFreeHeightField(p); }
};
struct CompactDeleter {
  void operator()(rcCompactHeightfield* p) const { rcFreeCompactHeightfield(p); }
};
struct ContourDeleter {
  void operator()(rcContourSet* p) const { rcFreeContourSet(p); }
};
struct PolyMeshDeleter {
  void operator()(rcPolyMesh* p) const { rcFreePolyMesh(p); }
};
struct DetailDeleter {
  void operator()(rcPolyMeshDetail* p) const { rcFreePolyMeshDetail(p); }
};

bool finite2(glm::vec2 v) { return std::isfinite(v.x) && std::isfinite(v.y); }

// Triangle soup with one area id per triangle.
struct Geometry {
  std::vector<float> verts;  // (x, y, z) per vertex
  std::vector<int> tris;
  std::vector<unsigned char> areas;

  int add_vertex(glm::vec2 ground, float y) {
    verts.insert(verts.end(), {ground.x, y, ground.y});
    return static_cast<int>(verts.size() / 3 - 1);
  }
  void add_quad(int a, int b, int c, int d, unsigned char area) {
    tris.insert(tris.end(), {a, b, c, a, c, d});
    areas.insert(areas.end(), {area, area});
  }
};

// A wall becomes a closed box: thickened by half the thickness on each side and past each end, so
// walls meeting at a corner leave no gap. A zero-length segment becomes a square pillar.
void add_wall_box(const WallSegment& wall, float thickness_m, float height_m, Geometry* geo) {
  glm::vec2 dir = wall.b - wall.a;
  const float length = glm::length(dir);
  dir = length > 1e-6f ? dir / length : glm::vec2(1.0f, 0.0f);
  const glm::vec2 side(-dir.y, dir.x);
  const float half = 0.5f * thickness_m;
  const glm::vec2 a = wall.a - dir * half, b = wall.b + dir * half;
  const glm::vec2 corners[4] = {a + side * half, b + side * half, b - side * half, a - side * half};
  int lo[4], hi[4];
  for (int i = 0; i < 4; ++i) {
    lo[i] = geo->add_vertex(corners[i], -kCellHeight_m);
    hi[i] = geo->add_vertex(corners[i], height_m);
  }
  geo->add_quad(hi[0], hi[1], hi[2], hi[3], RC_NULL_AREA);
  for (int i = 0; i < 4; ++i) {
    const int j = (i + 1) % 4;
    geo->add_quad(lo[i], lo[j], hi[j], hi[i], RC_NULL_AREA);
  }
}

}  // namespace

void NavMeshDeleter::operator()(dtNavMesh* navmesh) const { dtFreeNavMesh(navmesh); }

Result<NavMeshPtr> build_navmesh(const Scenario& scenario, const NavMeshBuildParams& params) {
  const std::string& file = scenario.source.empty() ? scenario.name : scenario.source;
  const float cs = params.cell_size_m;
  if (!std::isfinite(cs) || cs <= 0.0f) {
    return Status::AtField(file, "cell_size_m", "expected a finite size > 0 m");
  }
  if (!std::isfinite(params.agent_radius_m) || params.agent_radius_m <= 0.0f) {
    return Status::AtField(file, "agent radius", "expected a finite radius > 0 m");
  }
  const glm::vec2 lo = scenario.bounds_min, hi = scenario.bounds_max;
  if (!finite2(lo) || !finite2(hi) || !(hi.x > lo.x) || !(hi.y > lo.y)) {
    return Status::AtField(file, "bounds", "expected finite bounds with max > min");
  }
  const double cells_x = std::ceil((hi.x - lo.x) / cs), cells_z = std::ceil((hi.y - lo.y) / cs);
  if (cells_x * cells_z > kMaxCells || cells_x > kMaxCellsPerAxis || cells_z > kMaxCellsPerAxis) {
    return Status::AtField(file, "bounds",
                           "navmesh grid of " + std::to_string(cells_x) + " x " +
                               std::to_string(cells_z) + " cells is too large; raise cell_size_m");
  }

  Geometry geo;
  const int g0 = geo.add_vertex(lo, 0.0f), g1 = geo.add_vertex({hi.x, lo.y}, 0.0f);
  const int g2 = geo.add_vertex(hi, 0.0f), g3 = geo.add_vertex({lo.x, hi.y}, 0.0f);
  geo.add_quad(g0, g3, g2, g1, RC_WALKABLE_AREA);
  for (size_t i = 0; i < scenario.walls.size(); ++i) {
    if (!finite2(scenario.walls[i].a) || !finite2(scenario.walls[i].b)) {
      return Status::AtField(file, "walls[" + std::to_string(i) + "]",
                             "expected finite end points");
    }
    add_wall_box(scenario.walls[i], params.wall_thickness_m, params.wall_height_m, &geo);
  }

  rcConfig cfg{};
  cfg.cs = cs;
  cfg.ch = kCellHeight_m;
  cfg.walkableSlopeAngle = kWalkableSlope_deg;
  cfg.walkableHeight = static_cast<int>(std::ceil(kAgentHeight_m / cfg.ch));
  cfg.walkableClimb = static_cast<int>(std::floor(kAgentClimb_m / cfg.ch));
  cfg.walkableRadius = static_cast<int>(std::ceil(params.agent_radius_m / cs));
  cfg.maxEdgeLen = static_cast<int>(12.0f / cs);
  cfg.maxSimplificationError = 1.0f;  // [voxels]: contours stay within a cell of the eroded edge
  cfg.minRegionArea = static_cast<int>(std::ceil((0.5f / cs) * (0.5f / cs)));
  cfg.mergeRegionArea = static_cast<int>(std::ceil((2.0f / cs) * (2.0f / cs)));
  cfg.maxVertsPerPoly = DT_VERTS_PER_POLYGON;
  cfg.detailSampleDist = 6.0f * cs;
  cfg.detailSampleMaxError = cfg.ch;
  cfg.bmin[0] = lo.x;
  cfg.bmin[1] = -0.5f;
  cfg.bmin[2] = lo.y;
  cfg.bmax[0] = hi.x;
  cfg.bmax[1] = params.wall_height_m + 0.5f;
  cfg.bmax[2] = hi.y;
  rcCalcGridSize(cfg.bmin, cfg.bmax, cfg.cs, &cfg.width, &cfg.height);

  rcContext ctx(false);
  const auto fail = [&](const char* stage) {
    return Status::AtField(file, "navmesh", std::string("Recast failed at ") + stage);
  };
  std::unique_ptr<rcHeightfield, HeightfieldDeleter> solid(rcAllocHeightfield());
  if (!solid || !rcCreateHeightfield(&ctx, *solid, cfg.width, cfg.height, cfg.bmin, cfg.bmax,
                                     cfg.cs, cfg.ch)) {
    return fail("heightfield creation");
  }
  if (!rcRasterizeTriangles(&ctx, geo.verts.data(), static_cast<int>(geo.verts.size() / 3),
                            geo.tris.data(), geo.areas.data(), static_cast<int>(geo.areas.size()),
                            *solid, cfg.walkableClimb)) {
    return fail("rasterisation");
  }
  rcFilterLowHangingWalkableObstacles(&ctx, cfg.walkableClimb, *solid);
  rcFilterLedgeSpans(&ctx, cfg.walkableHeight, cfg.walkableClimb, *solid);
  rcFilterWalkableLowHeightSpans(&ctx, cfg.walkableHeight, *solid);

  std::unique_ptr<rcCompactHeightfield, CompactDeleter> chf(rcAllocCompactHeightfield());
  if (!chf ||
      !rcBuildCompactHeightfield(&ctx, cfg.walkableHeight, cfg.walkableClimb, *solid, *chf)) {
    return fail("compact heightfield");
  }
  solid.reset();
  if (!rcErodeWalkableArea(&ctx, cfg.walkableRadius, *chf)) return fail("erosion");
  if (!rcBuildDistanceField(&ctx, *chf)) return fail("distance field");
  if (!rcBuildRegions(&ctx, *chf, 0, cfg.minRegionArea, cfg.mergeRegionArea)) {
    return fail("regions");
  }
  std::unique_ptr<rcContourSet, ContourDeleter> contours(rcAllocContourSet());
  if (!contours ||
      !rcBuildContours(&ctx, *chf, cfg.maxSimplificationError, cfg.maxEdgeLen, *contours)) {
    return fail("contours");
  }
  std::unique_ptr<rcPolyMesh, PolyMeshDeleter> pmesh(rcAllocPolyMesh());
  if (!pmesh || !rcBuildPolyMesh(&ctx, *contours, cfg.maxVertsPerPoly, *pmesh)) {
    return fail("polygon mesh");
  }
  std::unique_ptr<rcPolyMeshDetail, DetailDeleter> dmesh(rcAllocPolyMeshDetail());
  if (!dmesh || !rcBuildPolyMeshDetail(&ctx, *pmesh, *chf, cfg.detailSampleDist,
                                       cfg.detailSampleMaxError, *dmesh)) {
    return fail("detail mesh");
  }
  if (pmesh->npolys == 0) {
    return Status::AtField(file, "navmesh",
                           "no walkable area: the bounds minus the walls and an agent-radius "
                           "margin leave nothing to walk on");
  }
  for (int i = 0; i < pmesh->npolys; ++i) {
    pmesh->flags[i] = pmesh->areas[i] == RC_WALKABLE_AREA ? kWalkableFlag : 0;
  }

  dtNavMeshCreateParams create{};
  create.verts = pmesh->verts;
  create.vertCount = pmesh->nverts;
  create.polys = pmesh->polys;
  create.polyAreas = pmesh->areas;
  create.polyFlags = pmesh->flags;
  create.polyCount = pmesh->npolys;
  create.nvp = pmesh->nvp;
  create.detailMeshes = dmesh->meshes;
  create.detailVerts = dmesh->verts;
  create.detailVertsCount = dmesh->nverts;
  create.detailTris = dmesh->tris;
  create.detailTriCount = dmesh->ntris;
  create.walkableHeight = kAgentHeight_m;
  create.walkableRadius = params.agent_radius_m;
  create.walkableClimb = kAgentClimb_m;
  for (int k = 0; k < 3; ++k) {
    create.bmin[k] = pmesh->bmin[k];
    create.bmax[k] = pmesh->bmax[k];
  }
  create.cs = cfg.cs;
  create.ch = cfg.ch;
  create.buildBvTree = true;
  unsigned char* data = nullptr;
  int data_size = 0;
  if (!dtCreateNavMeshData(&create, &data, &data_size)) {
    return fail("Detour tile creation (too many vertices? raise cell_size_m)");
  }
  NavMeshPtr navmesh(dtAllocNavMesh());
  if (!navmesh) {
    dtFree(data);
    return fail("navmesh allocation");
  }
  if (dtStatusFailed(navmesh->init(data, data_size, DT_TILE_FREE_DATA))) {
    dtFree(data);
    return fail("navmesh initialisation");
  }
  return navmesh;
}

}  // namespace gk
