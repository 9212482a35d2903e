#include "render/mesh_lod.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <meshoptimizer.h>
#include <glm/geometric.hpp>

namespace gk {
namespace {

// A level must drop at least this share of the previous level's triangles to be worth a draw
// call of its own.
constexpr float kMinReduction = 0.85f;

// Vertices are welded for simplification when every attribute agrees after rounding: positions to
// 1e-5 of the mesh's extent (a generator's poles and seams differ by float noise), normals,
// colours and weights to 1e-3. A welded vertex's triangles then use one of its copies, which has
// the same skinning and shading.
constexpr int kWeldKeyInts = 17;  // position 3, normal 3, colour 3, joints 4, weights 4

std::vector<uint32_t> weld(const SkinnedMesh& mesh, std::span<const uint32_t> indices,
                           float extent_m) {
  const size_t n = mesh.positions.size();
  const float position_step = 1e5f / std::max(extent_m, 1e-6f);
  const auto q = [](float v, float step) { return static_cast<int32_t>(std::lround(v * step)); };
  std::vector<int32_t> keys(n * kWeldKeyInts);
  for (size_t i = 0; i < n; ++i) {
    int32_t* k = &keys[i * kWeldKeyInts];
    const glm::vec3 color = mesh.colors.empty() ? glm::vec3(0.0f) : mesh.colors[i];
    for (int c = 0; c < 3; ++c) {
      k[c] = q(mesh.positions[i][c], position_step);
      k[3 + c] = q(mesh.normals[i][c], 1e3f);
      k[6 + c] = q(color[c], 1e3f);
    }
    for (int c = 0; c < 4; ++c) {
      k[9 + c] = mesh.joints[i][c];
      k[13 + c] = q(mesh.weights[i][c], 1e3f);
    }
  }
  std::vector<uint32_t> welded(indices.size());
  meshopt_generateShadowIndexBuffer(welded.data(), indices.data(), indices.size(), keys.data(), n,
                                    kWeldKeyInts * sizeof(int32_t), kWeldKeyInts * sizeof(int32_t));
  return welded;
}

// Signed volume enclosed by the triangles [m^3] (positive for a closed surface wound
// counter-clockwise seen from outside) and their area [m^2].
void volume_and_area(std::span<const glm::vec3> p, std::span<const uint32_t> idx,
                     double* out_volume, double* out_area) {
  double v = 0.0, a = 0.0;
  for (size_t t = 0; t + 2 < idx.size(); t += 3) {
    const glm::dvec3 p0(p[idx[t]]), p1(p[idx[t + 1]]), p2(p[idx[t + 2]]);
    v += glm::dot(p0, glm::cross(p1, p2)) / 6.0;
    a += 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
  }
  *out_volume = v;
  *out_area = a;
}

// Area-weighted face normals summed per vertex. The level's indices name one copy of each welded
// vertex, so the faces around it meet there; copies kept apart (a box's flat faces, an attribute
// seam) keep their own faces' normal.
std::vector<glm::vec3> level_normals(const SkinnedMesh& mesh, std::span<const uint32_t> idx) {
  std::vector<glm::vec3> normals(mesh.positions.size(), glm::vec3(0.0f));
  for (size_t t = 0; t + 2 < idx.size(); t += 3) {
    const glm::vec3& p0 = mesh.positions[idx[t]];
    const glm::vec3 face =
        glm::cross(mesh.positions[idx[t + 1]] - p0, mesh.positions[idx[t + 2]] - p0);
    for (int k = 0; k < 3; ++k) normals[idx[t + k]] += face;
  }
  for (size_t i = 0; i < normals.size(); ++i) {
    const float length = glm::length(normals[i]);
    // Unused vertices, and faces that cancel out, keep the mesh's normal.
    normals[i] = length > 1e-12f ? normals[i] / length : mesh.normals[i];
  }
  return normals;
}

}  // namespace

Result<MeshLodChain> build_mesh_lods(const SkinnedMesh& mesh, std::span<const uint32_t> indices,
                                     const MeshLodOptions& options) {
  const size_t n = mesh.positions.size();
  if (n == 0 || indices.empty() || indices.size() % 3 != 0) {
    return Status::Error("mesh lod: need vertices and a multiple of 3 indices, got " +
                         std::to_string(n) + " vertices, " + std::to_string(indices.size()) +
                         " indices");
  }
  if (mesh.normals.size() != n || mesh.joints.size() != n || mesh.weights.size() != n ||
      (!mesh.colors.empty() && mesh.colors.size() != n)) {
    return Status::Error(
        "mesh lod: normals/joints/weights/colors must have one entry per vertex (" +
        std::to_string(n) + ")");
  }
  for (size_t i = 0; i < indices.size(); ++i) {
    if (indices[i] >= n) {
      return Status::Error("mesh lod: index " + std::to_string(i) + " = " +
                           std::to_string(indices[i]) + " >= vertex count " + std::to_string(n));
    }
  }
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (size_t i = 0; i < n; ++i) {
    const glm::vec3& p = mesh.positions[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      return Status::Error("mesh lod: vertex " + std::to_string(i) + " is not finite");
    }
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  if (!(options.max_relative_error > 0.0f)) {
    return Status::Error("mesh lod: max_relative_error must be > 0");
  }
  float previous_share = 1.0f;
  for (float share : options.triangle_share) {
    if (!(share > 0.0f && share < previous_share)) {
      return Status::Error("mesh lod: triangle_share must decrease within (0, 1)");
    }
    previous_share = share;
  }

  const float* xyz = &mesh.positions[0].x;
  constexpr size_t kStride = sizeof(glm::vec3);
  MeshLodChain chain;
  MeshLodLevel full;
  full.indices.resize(indices.size());
  meshopt_optimizeVertexCache(full.indices.data(), indices.data(), indices.size(), n);
  chain.levels.push_back(std::move(full));

  double full_volume = 0.0, full_area = 0.0;
  volume_and_area(mesh.positions, indices, &full_volume, &full_area);
  const glm::vec3 size = hi - lo;
  const std::vector<uint32_t> welded = weld(mesh, indices, std::max({size.x, size.y, size.z}));
  // meshoptimizer's errors are relative to this extent; times it they are metres.
  const float scale = meshopt_simplifyScale(xyz, n, kStride);
  std::vector<uint32_t> scratch(indices.size());
  for (float share : options.triangle_share) {
    const MeshLodLevel& previous = chain.levels.back();
    const size_t target = std::max<size_t>(
        3, static_cast<size_t>(share * static_cast<float>(indices.size() / 3)) * 3);
    float relative_error = 0.0f;
    // From the full mesh each time: errors do not pile up through the chain.
    const size_t count =
        meshopt_simplify(scratch.data(), welded.data(), welded.size(), xyz, n, kStride, target,
                         options.max_relative_error, /*options=*/0, &relative_error);
    if (count < 3 ||
        static_cast<float>(count) > kMinReduction * static_cast<float>(previous.indices.size())) {
      break;  // the error cap or the topology stops here: lighter targets would stop here too
    }
    MeshLodLevel level;
    level.indices.resize(count);
    meshopt_optimizeVertexCache(level.indices.data(), scratch.data(), count, n);
    level.error_m = std::max(relative_error * scale, previous.error_m);
    level.normals = level_normals(mesh, level.indices);
    // Pushing a surface of area A out by d adds about d * A to its volume.
    double volume = 0.0, area = 0.0;
    volume_and_area(mesh.positions, level.indices, &volume, &area);
    if (full_volume > 0.0 && area > 0.0) {
      level.inflate_m =
          std::clamp(static_cast<float>((full_volume - volume) / area), 0.0f, level.error_m);
    }
    chain.levels.push_back(std::move(level));
  }
  return chain;
}

float pixels_per_metre(float proj_y_scale, int viewport_height_px, float depth_m) {
  if (!(depth_m > 0.0f)) return INFINITY;
  return proj_y_scale * 0.5f * static_cast<float>(viewport_height_px) / depth_m;
}

int choose_mesh_lod(std::span<const float> level_errors_m, float pixels_per_m,
                    const MeshLodSelection& selection, int current) {
  const int n = static_cast<int>(level_errors_m.size());
  if (n <= 1 || !(selection.max_error_px > 0.0f) || !(pixels_per_m >= 0.0f)) return 0;
  // Errors increase along the chain: the first level over the limit ends the search.
  const auto lightest_within = [&](float limit_px) {
    int best = 0;
    for (int l = 1; l < n && level_errors_m[l] * pixels_per_m <= limit_px; ++l) best = l;
    return best;
  };
  const int target = lightest_within(selection.max_error_px);
  if (current < 0 || current >= n || target <= current) return target;
  const float hysteresis = std::clamp(selection.hysteresis, 0.0f, 1.0f);
  return std::max(current, lightest_within(selection.max_error_px * (1.0f - hysteresis)));
}

}  // namespace gk
