#pragma once
// Skinned triangle mesh in the bind pose, for GPU skinning. Up to four influences per vertex.

#include <cstdint>
#include <vector>

#include <glm/gtc/type_precision.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace gk {

struct SkinnedMesh {
  std::vector<glm::vec3> positions;  // bind pose, model space [m]
  std::vector<glm::vec3> normals;
  std::vector<glm::vec3> colors;     // per-vertex base colour (linear RGB)
  std::vector<glm::u16vec4> joints;  // skeleton joint indices (already remapped to the Skeleton)
  std::vector<glm::vec4> weights;    // sum to 1
  std::vector<uint32_t> indices;     // triangles
  // Per skeleton joint: inverse of the joint's model-space bind transform (identity for joints
  // that influence no vertex).
  std::vector<glm::mat4> inverse_bind;
  int num_vertices() const { return static_cast<int>(positions.size()); }
  int num_triangles() const { return static_cast<int>(indices.size() / 3); }
};

}  // namespace gk
