// CrowdRenderer::add_mesh: validation, bounds, winding repair, the chain of lighter levels and the
// vertex layout of skinned.vert.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>

#include "render/crowd_renderer.h"

namespace gk {
namespace {

struct MeshVertex {  // matches the per-vertex attributes of skinned.vert
  glm::vec3 position;
  glm::vec3 normal;
  glm::vec3 color;
  glm::u16vec4 joints;
  glm::vec4 weights;
};

// Fraction of triangles whose orientation the normals must decide before a mesh is drawn with
// back-face culling (the rest have normals perpendicular to the face, i.e. unusable normals).
constexpr float kDecidableWinding = 0.99f;

// Front faces are defined by the vertex normals, not by the index order: generated meshes often
// wind a few triangles (caps, poles) the other way. Rewinds every triangle whose geometric normal
// opposes its vertex normals so that all are counter-clockwise seen from outside; returns false
// when too many triangles cannot be decided to cull back faces safely.
bool rewind_to_normals(const SkinnedMesh& mesh, std::vector<uint32_t>* out_indices) {
  *out_indices = mesh.indices;
  int decided = 0;
  for (size_t t = 0; t + 2 < out_indices->size(); t += 3) {
    uint32_t* tri = out_indices->data() + t;
    const glm::vec3 face = glm::cross(mesh.positions[tri[1]] - mesh.positions[tri[0]],
                                      mesh.positions[tri[2]] - mesh.positions[tri[0]]);
    const float d =
        glm::dot(face, mesh.normals[tri[0]] + mesh.normals[tri[1]] + mesh.normals[tri[2]]);
    if (d < 0.0f) std::swap(tri[1], tri[2]);
    decided += d != 0.0f;
  }
  return decided >= kDecidableWinding * static_cast<float>(mesh.num_triangles());
}

// Animation moves limbs outside the bind-pose bounds (stride, arm swing); the culling sphere is
// grown by this factor so agents at the screen edge never pop.
constexpr float kCullRadiusMargin = 1.3f;

}  // namespace

Result<int> CrowdRenderer::add_mesh(const SkinnedMesh& mesh, const MeshLodOptions& lod_options) {
  if (!initialized_) return Status::Error("add_mesh: renderer not initialised");
  const size_t n = mesh.positions.size();
  if (n == 0 || mesh.indices.empty() || mesh.indices.size() % 3 != 0) {
    return Status::Error("add_mesh: need vertices and a multiple of 3 indices, got " +
                         std::to_string(n) + " vertices, " + std::to_string(mesh.indices.size()) +
                         " indices");
  }
  if (mesh.normals.size() != n || mesh.joints.size() != n || mesh.weights.size() != n ||
      (!mesh.colors.empty() && mesh.colors.size() != n)) {
    return Status::Error(
        "add_mesh: normals/joints/weights/colors must have one entry per vertex (" +
        std::to_string(n) + ")");
  }
  for (size_t i = 0; i < mesh.indices.size(); ++i) {
    if (mesh.indices[i] >= n) {
      return Status::Error("add_mesh: index " + std::to_string(i) + " = " +
                           std::to_string(mesh.indices[i]) + " >= vertex count " +
                           std::to_string(n));
    }
  }
  std::vector<MeshVertex> vertices(n);
  MeshGpu gpu;
  float y_min = mesh.positions[0].y, y_max = y_min;
  for (const glm::vec3& p : mesh.positions) {
    y_min = std::min(y_min, p.y);
    y_max = std::max(y_max, p.y);
  }
  gpu.center_height_m = 0.5f * (y_min + y_max);
  float radius = 0.0f, low_radius = 0.0f;
  for (size_t i = 0; i < n; ++i) {
    const glm::vec3& p = mesh.positions[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      return Status::Error("add_mesh: vertex " + std::to_string(i) + " is not finite");
    }
    for (int k = 0; k < 4; ++k) {
      if (mesh.weights[i][k] > 0.0f)
        gpu.num_joints = std::max(gpu.num_joints, mesh.joints[i][k] + 1);
    }
    radius = std::max(radius, glm::length(p - glm::vec3(0.0f, gpu.center_height_m, 0.0f)));
    // The shadow follows the lower body (legs, feet), not outstretched bind-pose arms.
    if (p.y < y_min + 0.5f * (y_max - y_min)) {
      low_radius = std::max(low_radius, glm::length(glm::vec2(p.x, p.z)));
    }
    vertices[i] = {p, mesh.normals[i], mesh.colors.empty() ? glm::vec3(0.7f) : mesh.colors[i],
                   mesh.joints[i], mesh.weights[i]};
  }
  gpu.radius_m = radius * kCullRadiusMargin;
  gpu.shadow_radius_m = std::max(low_radius * 1.6f, 0.15f);
  std::vector<uint32_t> wound;
  gpu.cull_back_faces = rewind_to_normals(mesh, &wound);
  // Simplification keeps the winding, so the culling decided on the full mesh holds at every level.
  Result<MeshLodChain> chain = build_mesh_lods(mesh, wound, lod_options);
  if (!chain.ok()) return Status::Error("add_mesh: " + chain.message());
  // One buffer of each: level l's copy of the vertices (with its own normals) follows level
  // l - 1's, and its indices, offset to that copy, follow level l - 1's.
  std::vector<uint32_t> indices;
  gpu.num_lods = std::min(chain->num_levels(), kMaxMeshLods);
  vertices.resize(n * gpu.num_lods);
  for (int l = 0; l < gpu.num_lods; ++l) {
    const MeshLodLevel& level = chain->levels[l];
    gpu.lod_first[l] = static_cast<GLsizei>(indices.size());
    gpu.lod_count[l] = static_cast<GLsizei>(level.indices.size());
    gpu.lod_error_m[l] = level.error_m;
    gpu.lod_inflate_m[l] = level.inflate_m;
    const auto first_vertex = static_cast<uint32_t>(n * l);
    for (uint32_t i : level.indices) indices.push_back(first_vertex + i);
    if (l == 0) continue;
    for (size_t i = 0; i < n; ++i) {
      vertices[first_vertex + i] = vertices[i];
      if (level.normals.size() == n) vertices[first_vertex + i].normal = level.normals[i];
    }
  }

  glGenVertexArrays(1, &gpu.vao);
  glGenBuffers(1, &gpu.vertex_buffer);
  glGenBuffers(1, &gpu.index_buffer);
  glBindVertexArray(gpu.vao);
  glBindBuffer(GL_ARRAY_BUFFER, gpu.vertex_buffer);
  glBufferData(GL_ARRAY_BUFFER, vertices.size() * sizeof(MeshVertex), vertices.data(),
               GL_STATIC_DRAW);
  const auto offset = [](size_t o) { return reinterpret_cast<void*>(o); };
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(MeshVertex),
                        offset(offsetof(MeshVertex, position)));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(MeshVertex),
                        offset(offsetof(MeshVertex, normal)));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, sizeof(MeshVertex),
                        offset(offsetof(MeshVertex, color)));
  glEnableVertexAttribArray(3);
  glVertexAttribIPointer(3, 4, GL_UNSIGNED_SHORT, sizeof(MeshVertex),
                         offset(offsetof(MeshVertex, joints)));
  glEnableVertexAttribArray(4);
  glVertexAttribPointer(4, 4, GL_FLOAT, GL_FALSE, sizeof(MeshVertex),
                        offset(offsetof(MeshVertex, weights)));
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, gpu.index_buffer);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, indices.size() * sizeof(uint32_t), indices.data(),
               GL_STATIC_DRAW);
  // Instance attributes; their offsets are re-pointed per draw at this mesh's slice of instances.
  glBindBuffer(GL_ARRAY_BUFFER, instance_buffer_);
  glEnableVertexAttribArray(5);
  glVertexAttribDivisor(5, 1);
  glEnableVertexAttribArray(6);
  glVertexAttribDivisor(6, 1);
  glEnableVertexAttribArray(8);
  glVertexAttribDivisor(8, 1);
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);

  meshes_.push_back(gpu);
  bucket_first_.resize(meshes_.size() * kMaxMeshLods);
  bucket_count_.resize(meshes_.size() * kMaxMeshLods);
  return static_cast<int>(meshes_.size()) - 1;
}

}  // namespace gk
