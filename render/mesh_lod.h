#pragma once
// Mesh level of detail for distant agents: a chain of ever lighter index buffers over the SAME
// vertices (simplified with meshoptimizer on the bind-pose positions, so every kept vertex keeps
// its joints and weights and the lighter levels skin exactly like the full mesh; each level brings
// its own normals and how far to push it out), and the choice of a level per agent from its size
// on screen. docs/mesh_lod.md explains the numbers.
//
// The choice is by projected error, not by metres: each level knows how far (in the bind pose) its
// surface lies from the full mesh's [m]; an agent gets the lightest level whose error, times the
// pixels one metre covers at the agent's depth, stays under `max_error_px`. Below a pixel a switch
// moves no edge by a visible amount, so levels change without a visible pop and without a
// cross-fade; the hysteresis keeps an agent near a threshold from flickering between two levels.
// Built once per mesh at load time (allocates); the choice is a pure function of a few numbers.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "animation/mesh.h"
#include "common/status.h"

namespace gk {

inline constexpr int kMaxMeshLods = 4;  // the full mesh and up to three lighter levels

struct MeshLodOptions {
  // Share of the full mesh's triangles each lighter level aims at, heaviest first [Limit: (0, 1),
  // decreasing]. meshoptimizer stops short of a target where the topology (a closed capsule, a
  // seam) allows no further collapse or the error cap is reached; the chain ends at the first
  // level that comes out not clearly lighter (by 15 %) than the one before it.
  std::array<float, kMaxMeshLods - 1> triangle_share{0.35f, 0.12f, 0.06f};
  // Largest bind-pose error a level may have, as a share of the mesh's extent (its largest
  // bounding-box side) [Limit: > 0]: a cap so that no level turns the body into a blob.
  float max_relative_error = 0.05f;
};

struct MeshLodLevel {
  std::vector<uint32_t> indices;  // triangles over the mesh's own vertices
  float error_m = 0.0f;           // bind-pose distance of this surface from the full one [m]
  // How far to push this level's vertices out along their normals when drawing it [m], in
  // [0, error_m]: simplification keeps a subset of the vertices, so a curved part comes out
  // inscribed in the original and thinner (a limb's ring of 10 becomes a triangle); pushed out by
  // this much, the level encloses the full mesh's volume again and distant bodies keep their
  // width on screen. 0 for the full mesh and for meshes that enclose no volume.
  float inflate_m = 0.0f;
  // Vertex normals for drawing this level, one per mesh vertex (empty for the full mesh: its own).
  // Recomputed from the level's triangles: a simplified capsule keeps its pole rings and loses its
  // middle ones, and the poles' steep normals stretched over the whole body would shade it in
  // bands; vertices the level does not use keep the mesh's normal.
  std::vector<glm::vec3> normals;
};

// levels[0] is the full mesh (its indices as given, error 0); each further level has fewer
// triangles and a larger error than the one before. Every level's indices are ordered for the
// post-transform vertex cache.
struct MeshLodChain {
  std::vector<MeshLodLevel> levels;
  int num_levels() const { return static_cast<int>(levels.size()); }
};

// Builds the chain of `mesh` (its bind-pose vertices) drawn with the triangles `indices` (the
// mesh's own, or a re-wound copy of them). Validates the mesh's arrays, the indices (a multiple of
// 3, each < the vertex count) and the positions (finite); errors name what is at fault.
// Simplification keeps each triangle's winding, so a mesh wound for back-face culling stays so at
// every level. Vertices equal in every attribute (up to rounding: seams of a lat-long capsule, the
// points of its poles) are treated as one, so closed parts close and simplify down.
Result<MeshLodChain> build_mesh_lods(const SkinnedMesh& mesh, std::span<const uint32_t> indices,
                                     const MeshLodOptions& options = {});

struct MeshLodSelection {
  // Largest projected error of the level drawn [px] [Limit: >= 0; 0 keeps the full mesh].
  float max_error_px = 1.0f;
  // A lighter level is taken only when its error is below (1 - hysteresis) * max_error_px; a
  // heavier one as soon as the current level's error exceeds max_error_px [Limit: [0, 1)].
  float hysteresis = 0.25f;
};

// Pixels one metre covers at view depth `depth_m` for a vertical field of view whose projection
// matrix has `proj_y_scale` = 1 / tan(fov_y / 2), in a viewport `viewport_height_px` high.
// Infinite for depths at or behind the eye (the full mesh is then chosen).
float pixels_per_metre(float proj_y_scale, int viewport_height_px, float depth_m);

// The level for an agent whose mesh has `level_errors_m` (levels[i].error_m, increasing) and that
// covers `pixels_per_m` at its depth, given the level it was drawn with last (`current`; negative
// or out of range: none yet). Pure; never returns a level whose error exceeds max_error_px, except
// level 0.
int choose_mesh_lod(std::span<const float> level_errors_m, float pixels_per_m,
                    const MeshLodSelection& selection, int current);

}  // namespace gk
