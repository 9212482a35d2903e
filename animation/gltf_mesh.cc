// Skinned mesh of a glTF file: vertices of every triangle primitive, skin joints remapped to the
// skeleton, weights normalised, inverse bind matrices per skeleton joint.

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_inverse.hpp>

#include "animation/gltf_internal.h"

namespace gk::internal {
namespace {

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Fills one primitive's vertices into mesh; skin joint numbers are remapped to skeleton joints.
Status load_primitive(const tinygltf::Model& model, const tinygltf::Primitive& prim,
                      const std::string& field, const std::vector<int>& joint_of_node,
                      const glm::mat4& bake, const std::string& file, SkinnedMesh* mesh) {
  auto attribute = [&](const char* name, int type, bool required) -> Result<AccessorView> {
    auto it = prim.attributes.find(name);
    if (it == prim.attributes.end()) {
      if (required) return Status::AtField(file, field + ".attributes", std::string("no ") + name);
      return AccessorView{};
    }
    return view_accessor(model, it->second, type, file, field + ".attributes." + name);
  };
  Result<AccessorView> pos = attribute("POSITION", TINYGLTF_TYPE_VEC3, true);
  GK_RETURN_IF_ERROR(pos);
  Result<AccessorView> nrm = attribute("NORMAL", TINYGLTF_TYPE_VEC3, false);
  GK_RETURN_IF_ERROR(nrm);
  Result<AccessorView> jnt = attribute("JOINTS_0", TINYGLTF_TYPE_VEC4, true);
  GK_RETURN_IF_ERROR(jnt);
  Result<AccessorView> wgt = attribute("WEIGHTS_0", TINYGLTF_TYPE_VEC4, true);
  GK_RETURN_IF_ERROR(wgt);
  const size_t nv = pos->count;
  if ((nrm->data && nrm->count != nv) || jnt->count != nv || wgt->count != nv) {
    return Status::AtField(file, field + ".attributes", "attribute counts differ from POSITION");
  }
  glm::vec3 color(1.0f);
  if (prim.material >= 0 && prim.material < static_cast<int>(model.materials.size())) {
    const std::vector<double>& f =
        model.materials[prim.material].pbrMetallicRoughness.baseColorFactor;
    if (f.size() >= 3) color = glm::vec3(f[0], f[1], f[2]);
  }
  const size_t first = mesh->positions.size();
  const glm::mat3 normal_matrix = glm::inverseTranspose(glm::mat3(bake));
  const size_t num_skin = model.skins[0].joints.size();
  for (size_t v = 0; v < nv; ++v) {
    const glm::vec3 p(pos->get(v, 0), pos->get(v, 1), pos->get(v, 2));
    glm::vec3 n = nrm->data ? glm::vec3(nrm->get(v, 0), nrm->get(v, 1), nrm->get(v, 2))
                            : glm::vec3(0.0f, 1.0f, 0.0f);
    if (!finite(p) || !finite(n)) return Status::AtField(file, field, "non-finite vertex data");
    n = normal_matrix * n;
    const float nl = glm::length(n);
    mesh->positions.push_back(glm::vec3(bake * glm::vec4(p, 1.0f)));
    mesh->normals.push_back(nl > 0.0f ? n / nl : glm::vec3(0.0f, 1.0f, 0.0f));
    mesh->colors.push_back(color);
    glm::u16vec4 joints;
    glm::vec4 w;
    for (int c = 0; c < 4; ++c) {
      const uint32_t k = jnt->get_uint(v, c);
      if (k >= num_skin) {
        return Status::AtField(file, field + ".attributes.JOINTS_0",
                               "vertex " + std::to_string(v) + " uses joint " + std::to_string(k) +
                                   " (skin has " + std::to_string(num_skin) + ")");
      }
      joints[c] = static_cast<uint16_t>(joint_of_node[model.skins[0].joints[k]]);
      w[c] = std::max(0.0f, wgt->get(v, c));
    }
    const float sum = w.x + w.y + w.z + w.w;
    // A vertex with no weight follows its first joint rather than collapsing to the origin.
    w = std::isfinite(sum) && sum > 0.0f ? w / sum : glm::vec4(1.0f, 0.0f, 0.0f, 0.0f);
    mesh->joints.push_back(joints);
    mesh->weights.push_back(w);
  }
  if (prim.indices >= 0) {
    Result<AccessorView> ind =
        view_accessor(model, prim.indices, TINYGLTF_TYPE_SCALAR, file, field + ".indices");
    GK_RETURN_IF_ERROR(ind);
    if (ind->count % 3 != 0) return Status::AtField(file, field + ".indices", "not triangles");
    for (size_t i = 0; i < ind->count; ++i) {
      const uint32_t k = ind->get_uint(i, 0);
      if (k >= nv) {
        return Status::AtField(
            file, field + ".indices",
            "index " + std::to_string(k) + " out of range (" + std::to_string(nv) + " vertices)");
      }
      mesh->indices.push_back(static_cast<uint32_t>(first + k));
    }
  } else {
    for (size_t k = 0; k + 2 < nv; k += 3) {
      for (size_t c = 0; c < 3; ++c) mesh->indices.push_back(static_cast<uint32_t>(first + k + c));
    }
  }
  return Status::Ok();
}

}  // namespace

Result<std::shared_ptr<const SkinnedMesh>> load_skinned_mesh(const tinygltf::Model& model, int node,
                                                             const glm::mat4& bake,
                                                             const std::vector<int>& joint_of_node,
                                                             int num_joints,
                                                             const std::string& file) {
  const std::string nfield = "nodes[" + std::to_string(node) + "]";
  if (model.nodes[node].mesh >= static_cast<int>(model.meshes.size())) {
    return Status::AtField(file, nfield + ".mesh", "index out of range");
  }
  auto mesh = std::make_shared<SkinnedMesh>();
  const tinygltf::Mesh& m = model.meshes[model.nodes[node].mesh];
  const std::string mfield = "meshes[" + std::to_string(model.nodes[node].mesh) + "]";
  for (size_t i = 0; i < m.primitives.size(); ++i) {
    if (m.primitives[i].mode != TINYGLTF_MODE_TRIANGLES && m.primitives[i].mode != -1) continue;
    GK_RETURN_IF_ERROR(load_primitive(model, m.primitives[i],
                                      mfield + ".primitives[" + std::to_string(i) + "]",
                                      joint_of_node, bake, file, mesh.get()));
  }
  const tinygltf::Skin& skin = model.skins[0];
  mesh->inverse_bind.assign(num_joints, glm::mat4(1.0f));
  if (skin.inverseBindMatrices >= 0) {
    Result<AccessorView> ibm = view_accessor(model, skin.inverseBindMatrices, TINYGLTF_TYPE_MAT4,
                                             file, "skins[0].inverseBindMatrices");
    GK_RETURN_IF_ERROR(ibm);
    if (ibm->count < skin.joints.size()) {
      return Status::AtField(file, "skins[0].inverseBindMatrices",
                             std::to_string(ibm->count) + " matrices for " +
                                 std::to_string(skin.joints.size()) + " joints");
    }
    const glm::mat4 unbake = glm::inverse(bake);
    for (size_t k = 0; k < skin.joints.size(); ++k) {
      glm::mat4 m4;
      for (int c = 0; c < 16; ++c) m4[c / 4][c % 4] = ibm->get(k, c);
      mesh->inverse_bind[joint_of_node[skin.joints[k]]] = m4 * unbake;
    }
  }
  return std::shared_ptr<const SkinnedMesh>(std::move(mesh));
}

}  // namespace gk::internal
