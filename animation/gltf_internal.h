#pragma once
// glTF loader internals (private to animation/). tinygltf parses the JSON and the buffers, but an
// accessor's offset, count and stride still come from the file and must be checked against the
// buffer before any element is read.

#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>

#include <tiny_gltf.h>

#include "animation/mesh.h"
#include "common/status.h"

namespace gk::internal {

struct AccessorView {
  const uint8_t* data = nullptr;
  size_t stride = 0;
  size_t count = 0;
  int component_type = 0;
  int num_components = 0;
  bool normalized = false;

  // Component c of element i as a float (normalised integers mapped to [0, 1] or [-1, 1]).
  float get(size_t i, int c) const {
    const uint8_t* p = data + i * stride;
    switch (component_type) {
      case TINYGLTF_COMPONENT_TYPE_FLOAT:
        return load<float>(p, c);
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return scale(load<uint8_t>(p, c), 255.0f);
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        return scale(load<uint16_t>(p, c), 65535.0f);
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        return static_cast<float>(load<uint32_t>(p, c));
      case TINYGLTF_COMPONENT_TYPE_BYTE:
        return signed_scale(load<int8_t>(p, c), 127.0f);
      case TINYGLTF_COMPONENT_TYPE_SHORT:
        return signed_scale(load<int16_t>(p, c), 32767.0f);
      default:
        return 0.0f;
    }
  }
  // Component c of element i as an unsigned integer (indices, joint numbers).
  uint32_t get_uint(size_t i, int c) const {
    const uint8_t* p = data + i * stride;
    switch (component_type) {
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return load<uint8_t>(p, c);
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        return load<uint16_t>(p, c);
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        return load<uint32_t>(p, c);
      default:
        return 0xffffffffu;
    }
  }

 private:
  template <typename T>
  static T load(const uint8_t* p, int c) {
    T v;
    std::memcpy(&v, p + c * sizeof(T), sizeof(T));  // buffers need not be aligned
    return v;
  }
  float scale(float v, float max) const { return normalized ? v / max : v; }
  float signed_scale(float v, float max) const {
    return normalized ? (v / max < -1.0f ? -1.0f : v / max) : v;
  }
};

inline int component_size(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return 4;
    default:
      return 0;
  }
}

// Checks accessors[index] (of type `type`, e.g. TINYGLTF_TYPE_VEC3) against its buffer view and
// buffer; `field` names where the index came from, for the message.
inline Result<AccessorView> view_accessor(const tinygltf::Model& model, int index, int type,
                                          const std::string& file, const std::string& field) {
  if (index < 0 || index >= static_cast<int>(model.accessors.size())) {
    return Status::AtField(file, field,
                           "accessor index " + std::to_string(index) + " out of range (" +
                               std::to_string(model.accessors.size()) + " accessors)");
  }
  const tinygltf::Accessor& acc = model.accessors[index];
  const std::string where = "accessors[" + std::to_string(index) + "]";
  if (acc.type != type) {
    return Status::AtField(file, where,
                           "unexpected type " + std::to_string(acc.type) + " for " + field +
                               " (expected " + std::to_string(type) + ")");
  }
  if (acc.sparse.isSparse) return Status::AtField(file, where, "sparse accessors not supported");
  const int comp = component_size(acc.componentType);
  if (comp == 0) return Status::AtField(file, where, "unknown componentType");
  if (acc.bufferView < 0 || acc.bufferView >= static_cast<int>(model.bufferViews.size())) {
    return Status::AtField(file, where + ".bufferView",
                           "index " + std::to_string(acc.bufferView) + " out of range (" +
                               std::to_string(model.bufferViews.size()) + " bufferViews)");
  }
  const tinygltf::BufferView& view = model.bufferViews[acc.bufferView];
  if (view.buffer < 0 || view.buffer >= static_cast<int>(model.buffers.size())) {
    return Status::AtField(file, "bufferViews[" + std::to_string(acc.bufferView) + "].buffer",
                           "index out of range");
  }
  const uint64_t buffer_size = model.buffers[view.buffer].data.size();
  const uint64_t num_components = static_cast<uint64_t>(tinygltf::GetNumComponentsInType(type));
  const uint64_t elem = num_components * comp;
  const uint64_t stride = view.byteStride ? view.byteStride : elem;
  const uint64_t start = static_cast<uint64_t>(view.byteOffset) + acc.byteOffset;
  if (static_cast<uint64_t>(view.byteOffset) + view.byteLength > buffer_size ||
      static_cast<uint64_t>(view.byteOffset) > buffer_size) {
    return Status::AtField(
        file, "bufferViews[" + std::to_string(acc.bufferView) + "]",
        "extends past the end of its buffer (" + std::to_string(buffer_size) + " bytes)");
  }
  const uint64_t view_end = static_cast<uint64_t>(view.byteOffset) + view.byteLength;
  // count * stride is compared by division so that a huge count cannot overflow.
  if (stride < elem || start > view_end ||
      (acc.count > 0 && (acc.count - 1 > (view_end - start) / stride ||
                         start + (acc.count - 1) * stride + elem > view_end))) {
    return Status::AtField(file, where,
                           std::to_string(acc.count) + " elements of " + std::to_string(elem) +
                               " bytes do not fit in bufferView " + std::to_string(acc.bufferView) +
                               " (" + std::to_string(view.byteLength) + " bytes)");
  }
  AccessorView out;
  out.data = model.buffers[view.buffer].data.data() + start;
  out.stride = stride;
  out.count = acc.count;
  out.component_type = acc.componentType;
  out.num_components = static_cast<int>(num_components);
  out.normalized = acc.normalized;
  return out;
}

// The skinned mesh of `node` (which uses skin 0). Its vertices are transformed by `bake` and the
// inverse bind matrices multiplied by inverse(bake), so that skinning gives the same result.
// joint_of_node maps glTF nodes to skeleton joints.
Result<std::shared_ptr<const SkinnedMesh>> load_skinned_mesh(const tinygltf::Model& model, int node,
                                                             const glm::mat4& bake,
                                                             const std::vector<int>& joint_of_node,
                                                             int num_joints,
                                                             const std::string& file);

}  // namespace gk::internal
