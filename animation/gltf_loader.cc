// glTF 2.0 / GLB loader: skeleton from the first skin, every animation resampled as a clip, and
// the skinned mesh. tinygltf parses; every index and accessor range is checked here.

#include "animation/gltf_loader.h"

#include "animation/bvh_loader.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/gtx/matrix_decompose.hpp>
#include <glm/gtx/quaternion.hpp>

#include "animation/gltf_internal.h"
#include "animation/ik_rig.h"
#include "animation/loader_internal.h"
#include "animation/mesh.h"
#include "common/ascii.h"
#include "common/file_io.h"
#include "common/text_snippet.h"

namespace gk {
namespace {

using internal::AccessorView;
using internal::view_accessor;

struct Rigid {
  glm::vec3 t{0.0f};
  glm::quat r{1.0f, 0.0f, 0.0f, 0.0f};
};

std::string idx(const std::string& base, size_t i) { return base + "[" + std::to_string(i) + "]"; }

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// A node's local transform as translation + rotation; skeletons carry no scale, so scale is
// dropped (the mannequin's scales are 1 to 1e-7).
Result<Rigid> node_rigid(const tinygltf::Node& node, const std::string& file,
                         const std::string& field) {
  Rigid out;
  if (node.matrix.size() == 16) {
    glm::mat4 m = glm::make_mat4(node.matrix.data());
    glm::vec3 scale, skew;
    glm::vec4 persp;
    if (!glm::decompose(m, scale, out.r, out.t, skew, persp)) {
      return Status::AtField(file, field + ".matrix", "not a decomposable transform");
    }
  } else {
    if (node.translation.size() == 3) {
      out.t = glm::vec3(node.translation[0], node.translation[1], node.translation[2]);
    }
    if (node.rotation.size() == 4) {
      out.r = glm::quat(static_cast<float>(node.rotation[3]), static_cast<float>(node.rotation[0]),
                        static_cast<float>(node.rotation[1]), static_cast<float>(node.rotation[2]));
    }
  }
  const float len = glm::length(out.r);
  if (!finite(out.t) || !std::isfinite(len) || len < 1e-6f) {
    return Status::AtField(file, field, "translation/rotation not finite or zero rotation");
  }
  out.r = out.r / len;
  return out;
}

Rigid compose(const Rigid& a, const Rigid& b) { return {a.t + a.r * b.t, a.r * b.r}; }

glm::mat4 to_mat4(const Rigid& x) {
  return glm::translate(glm::mat4(1.0f), x.t) * glm::toMat4(x.r);
}

struct SkeletonBuild {
  std::shared_ptr<Skeleton> skeleton;
  std::vector<int> node_of_joint;  // skeleton joint -> glTF node
  std::vector<int> joint_of_node;  // glTF node -> skeleton joint or -1
  std::vector<Rigid> above;        // per joint: baked transform of non-joint ancestors (roots)
  std::vector<int> skin_joint;     // skeleton joint -> index in skin.joints or -1
};

Result<SkeletonBuild> build_skeleton(const tinygltf::Model& model, const std::vector<int>& parent,
                                     const std::string& file) {
  const tinygltf::Skin& skin = model.skins[0];
  const int num_nodes = static_cast<int>(model.nodes.size());
  std::vector<char> needed(num_nodes, 0);
  for (size_t k = 0; k < skin.joints.size(); ++k) {
    const int n = skin.joints[k];
    if (n < 0 || n >= num_nodes) {
      return Status::AtField(
          file, idx("skins[0].joints", k),
          "node " + std::to_string(n) + " out of range (" + std::to_string(num_nodes) + " nodes)");
    }
    needed[n] = 1;
  }
  if (skin.joints.empty()) return Status::AtField(file, "skins[0].joints", "empty");
  // Nodes between two skin joints are joints too, or the hierarchy would break apart.
  for (int n : skin.joints) {
    std::vector<int> path;
    for (int p = parent[n]; p >= 0; p = parent[p]) {
      if (needed[p] == 1) {
        for (int q : path) needed[q] = 2;
        break;
      }
      path.push_back(p);
    }
  }
  std::vector<int> order(skin.joints.begin(), skin.joints.end());
  for (int n = 0; n < num_nodes; ++n) {
    if (needed[n] == 2) order.push_back(n);
  }
  std::vector<int> depth(num_nodes, 0);
  for (int n : order) {
    for (int p = parent[n]; p >= 0; p = parent[p]) ++depth[n];
  }
  // Parents first: sort by depth only when the skin's own order is not already topological.
  SkeletonBuild b;
  b.joint_of_node.assign(num_nodes, -1);
  bool topological = true;
  for (size_t i = 0; i < order.size(); ++i) {
    b.joint_of_node[order[i]] = static_cast<int>(i);
    if (parent[order[i]] >= 0 && needed[parent[order[i]]] &&
        b.joint_of_node[parent[order[i]]] < 0) {
      topological = false;
    }
  }
  if (!topological) {
    std::stable_sort(order.begin(), order.end(), [&](int a, int c) { return depth[a] < depth[c]; });
    for (size_t i = 0; i < order.size(); ++i) b.joint_of_node[order[i]] = static_cast<int>(i);
  }
  if (order.size() > 32767) return Status::AtField(file, "skins[0].joints", "too many joints");
  b.skeleton = std::make_shared<Skeleton>();
  Skeleton& s = *b.skeleton;
  b.node_of_joint = order;
  b.skin_joint.assign(order.size(), -1);
  for (size_t k = 0; k < skin.joints.size(); ++k) b.skin_joint[b.joint_of_node[skin.joints[k]]] = k;
  for (int n : order) {
    const std::string field = idx("nodes", n);
    Result<Rigid> local = node_rigid(model.nodes[n], file, field);
    GK_RETURN_IF_ERROR(local);
    Rigid above;
    int p = parent[n];
    if (p >= 0 && !needed[p]) {
      // The non-joint ancestors above a top joint (e.g. an armature node) are folded into it.
      for (; p >= 0; p = parent[p]) {
        Result<Rigid> up = node_rigid(model.nodes[p], file, idx("nodes", p));
        GK_RETURN_IF_ERROR(up);
        above = compose(*up, above);
      }
      p = -1;
    }
    const Rigid rest = compose(above, *local);
    s.names.push_back(model.nodes[n].name.empty() ? "node_" + std::to_string(n)
                                                  : model.nodes[n].name);
    s.parents.push_back(static_cast<int16_t>(p >= 0 ? b.joint_of_node[p] : -1));
    s.rest_translations.push_back(rest.t);
    s.rest_rotations.push_back(rest.r);
    b.above.push_back(above);
  }
  GK_RETURN_IF_ERROR(validate_skeleton(s, file));
  return b;
}

// Key rate of one animation: the smallest median key spacing of its samplers with 3+ keys (two-key
// samplers are constant channels spanning the whole clip and say nothing about the rate).
float key_rate(const std::vector<std::vector<float>>& times) {
  float best_dt = 0.0f;
  for (const std::vector<float>& t : times) {
    if (t.size() < 3) continue;
    std::vector<float> dt;
    for (size_t i = 1; i < t.size(); ++i) dt.push_back(t[i] - t[i - 1]);
    std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
    const float med = dt[dt.size() / 2];
    if (med > 0.0f && (best_dt == 0.0f || med < best_dt)) best_dt = med;
  }
  if (best_dt <= 0.0f) return 0.0f;
  float fps = 1.0f / best_dt;
  if (std::abs(fps - std::round(fps)) < 0.05f) fps = std::round(fps);
  return std::clamp(fps, 1.0f, 1000.0f);
}

struct Track {
  int joint = -1;
  bool rotation = false;
  bool step = false;
  int stride = 1;  // 3 for CUBICSPLINE (in-tangent, value, out-tangent): the value is used
  AccessorView out;
  std::vector<float> times;
};

glm::vec4 track_value(const Track& tr, size_t key) {
  const size_t i = key * tr.stride + (tr.stride == 3 ? 1 : 0);
  glm::vec4 v(0.0f);
  for (int c = 0; c < (tr.rotation ? 4 : 3); ++c) v[c] = tr.out.get(i, c);
  return v;
}

void sample_track(const Track& tr, float t, glm::vec3* trans, glm::quat* rot) {
  const std::vector<float>& k = tr.times;
  size_t i = std::upper_bound(k.begin(), k.end(), t) - k.begin();
  glm::vec4 v;
  if (i == 0 || i == k.size() || tr.step) {
    v = track_value(tr, i == 0 ? 0 : i - 1);
  } else {
    const float span = k[i] - k[i - 1];
    const float a = span > 0.0f ? (t - k[i - 1]) / span : 0.0f;
    const glm::vec4 v0 = track_value(tr, i - 1), v1 = track_value(tr, i);
    if (tr.rotation) {
      const glm::quat q =
          glm::slerp(glm::quat(v0.w, v0.x, v0.y, v0.z), glm::quat(v1.w, v1.x, v1.y, v1.z), a);
      v = glm::vec4(q.x, q.y, q.z, q.w);
    } else {
      v = glm::mix(v0, v1, a);
    }
  }
  if (tr.rotation) {
    const glm::quat q(v.w, v.x, v.y, v.z);
    const float len = glm::length(q);
    if (std::isfinite(len) && len > 1e-6f) *rot = q / len;
  } else if (finite(glm::vec3(v))) {
    *trans = glm::vec3(v);
  }
}

Result<Clip> load_animation(const tinygltf::Model& model, size_t a, const SkeletonBuild& b,
                            float fallback_fps, const std::string& file) {
  const tinygltf::Animation& anim = model.animations[a];
  const std::string base = idx("animations", a);
  std::vector<Track> tracks;
  for (size_t c = 0; c < anim.channels.size(); ++c) {
    const tinygltf::AnimationChannel& ch = anim.channels[c];
    const std::string field = base + idx(".channels", c);
    if (ch.sampler < 0 || ch.sampler >= static_cast<int>(anim.samplers.size())) {
      return Status::AtField(file, field + ".sampler",
                             "index " + std::to_string(ch.sampler) + " out of range (" +
                                 std::to_string(anim.samplers.size()) + " samplers)");
    }
    if (ch.target_node < 0 || ch.target_node >= static_cast<int>(model.nodes.size())) {
      return Status::AtField(file, field + ".target.node",
                             "index " + std::to_string(ch.target_node) + " out of range (" +
                                 std::to_string(model.nodes.size()) + " nodes)");
    }
    const int joint = b.joint_of_node[ch.target_node];
    const bool rotation = ch.target_path == "rotation";
    if (joint < 0 || (!rotation && ch.target_path != "translation")) continue;  // scale, weights
    const tinygltf::AnimationSampler& smp = anim.samplers[ch.sampler];
    const std::string sfield = base + idx(".samplers", ch.sampler);
    Track tr;
    tr.joint = joint;
    tr.rotation = rotation;
    tr.step = smp.interpolation == "STEP";
    tr.stride = smp.interpolation == "CUBICSPLINE" ? 3 : 1;
    Result<AccessorView> in =
        view_accessor(model, smp.input, TINYGLTF_TYPE_SCALAR, file, sfield + ".input");
    GK_RETURN_IF_ERROR(in);
    Result<AccessorView> out =
        view_accessor(model, smp.output, rotation ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3, file,
                      sfield + ".output");
    GK_RETURN_IF_ERROR(out);
    if (in->count == 0 || out->count != in->count * tr.stride) {
      return Status::AtField(file, sfield,
                             std::to_string(in->count) + " key times but " +
                                 std::to_string(out->count) + " output values");
    }
    tr.out = *out;
    for (size_t k = 0; k < in->count; ++k) {
      const float t = in->get(k, 0);
      if (!std::isfinite(t) || (k > 0 && t < tr.times.back())) {
        return Status::AtField(file, sfield + ".input", "key times not finite and increasing");
      }
      tr.times.push_back(t);
    }
    tracks.push_back(std::move(tr));
  }
  float t0 = 0.0f, t1 = 0.0f;
  std::vector<std::vector<float>> all_times;
  for (size_t i = 0; i < tracks.size(); ++i) {
    t0 = i == 0 ? tracks[i].times.front() : std::min(t0, tracks[i].times.front());
    t1 = i == 0 ? tracks[i].times.back() : std::max(t1, tracks[i].times.back());
    all_times.push_back(tracks[i].times);
  }
  float fps = key_rate(all_times);
  if (fps <= 0.0f) fps = fallback_fps;
  const double frames = std::round(static_cast<double>(t1 - t0) * fps) + 1.0;
  const int num_joints = b.skeleton->num_joints();
  if (frames * num_joints > static_cast<double>(1 << 24)) {
    return Status::AtField(file, base,
                           "duration " + std::to_string(t1 - t0) + " s at " + std::to_string(fps) +
                               " fps is too long");
  }
  Clip clip;
  clip.name = anim.name.empty() ? base : anim.name;
  clip.source = file;
  clip.fps = fps;
  clip.num_frames = static_cast<int>(frames);
  clip.num_joints = num_joints;
  clip.rotations.resize(static_cast<size_t>(clip.num_frames) * num_joints);
  clip.translations.resize(clip.rotations.size());
  std::vector<Rigid> rest(num_joints), local(num_joints);
  for (int j = 0; j < num_joints; ++j) {
    Result<Rigid> r = node_rigid(model.nodes[b.node_of_joint[j]], file, "");
    rest[j] = r.ok() ? *r : Rigid{};  // checked by build_skeleton already
  }
  for (int f = 0; f < clip.num_frames; ++f) {
    local = rest;  // joints without a channel keep their rest value
    const float t = t0 + static_cast<float>(f) / fps;
    for (const Track& tr : tracks) sample_track(tr, t, &local[tr.joint].t, &local[tr.joint].r);
    for (int j = 0; j < num_joints; ++j) {
      const Rigid x = compose(b.above[j], local[j]);
      clip.rotations[static_cast<size_t>(f) * num_joints + j] = x.r;
      clip.translations[static_cast<size_t>(f) * num_joints + j] = x.t;
    }
  }
  return clip;
}

// A forced unit scale (files exported in other units despite the specification) scales every
// translation; inverse binds become S * IBM * S^-1 so that skinning stays consistent.
void apply_scale(float s, Skeleton* skeleton, std::vector<Clip>* clips,
                 std::shared_ptr<const SkinnedMesh>* mesh) {
  for (glm::vec3& t : skeleton->rest_translations) t *= s;
  for (Clip& c : *clips) {
    for (glm::vec3& t : c.translations) t *= s;
  }
  if (!*mesh) return;
  auto scaled = std::make_shared<SkinnedMesh>(**mesh);
  for (glm::vec3& p : scaled->positions) p *= s;
  const glm::mat4 up = glm::scale(glm::mat4(1.0f), glm::vec3(s));
  const glm::mat4 down = glm::scale(glm::mat4(1.0f), glm::vec3(1.0f / s));
  for (glm::mat4& m : scaled->inverse_bind) m = up * m * down;
  *mesh = std::move(scaled);
}

// tinygltf's errors may quote the file (a JSON parse error of a binary file): keep them
// printable.
Status tinygltf_error(const std::string& path, const std::string& err) {
  return Status::Error(path + ": " +
                       (err.empty() ? "cannot load glTF" : printable_snippet(err, 400)));
}

// Everything after tinygltf's parse: the skeleton, the clips and the mesh, every index checked.
Result<ClipSet> clips_from_model(const tinygltf::Model& model, const std::string& path,
                                 const LoadOptions& options) {
  if (model.skins.empty()) return Status::AtField(path, "skins", "no skin (a skeleton is needed)");

  // Parent of every node, rejecting shared children and cycles before anything walks up the tree.
  const int num_nodes = static_cast<int>(model.nodes.size());
  std::vector<int> parent(num_nodes, -1);
  for (int n = 0; n < num_nodes; ++n) {
    for (size_t c = 0; c < model.nodes[n].children.size(); ++c) {
      const int child = model.nodes[n].children[c];
      if (child < 0 || child >= num_nodes || child == n || parent[child] >= 0) {
        return Status::AtField(
            path, idx("nodes", n) + idx(".children", c),
            "node " + std::to_string(child) + " out of range or already a child");
      }
      parent[child] = n;
    }
  }
  for (int n = 0; n < num_nodes; ++n) {
    int steps = 0;
    for (int p = parent[n]; p >= 0; p = parent[p]) {
      if (++steps > num_nodes) return Status::AtField(path, idx("nodes", n), "cycle in hierarchy");
    }
  }

  Result<SkeletonBuild> build = build_skeleton(model, parent, path);
  GK_RETURN_IF_ERROR(build);
  detect_joint_roles(build->skeleton.get());
  if (!options.role_manifest.empty()) {
    GK_RETURN_IF_ERROR(apply_role_manifest(options.role_manifest, build->skeleton.get()));
  }
  ClipSet set;
  set.source = path;
  set.scale_m_per_unit = 1.0f;
  set.scale_reason = "glTF: metres by specification";

  // Animations made only of two-key (constant) channels borrow the rate of the others.
  float fallback_fps = 0.0f;
  for (const tinygltf::Animation& anim : model.animations) {
    std::vector<std::vector<float>> times;
    for (const tinygltf::AnimationSampler& s : anim.samplers) {
      Result<AccessorView> in = view_accessor(model, s.input, TINYGLTF_TYPE_SCALAR, path, "input");
      if (!in.ok() || in->count > 100000) continue;
      times.emplace_back();
      for (size_t k = 0; k < in->count; ++k) times.back().push_back(in->get(k, 0));
    }
    fallback_fps = std::max(fallback_fps, key_rate(times));
  }
  if (fallback_fps <= 0.0f) fallback_fps = 30.0f;

  const float tolerance = internal::loop_tolerance_m(*build->skeleton);
  for (size_t a = 0; a < model.animations.size(); ++a) {
    Result<Clip> clip = load_animation(model, a, *build, fallback_fps, path);
    GK_RETURN_IF_ERROR(clip);
    internal::finalize_loop(&clip.value(), *build->skeleton, tolerance);
    GK_RETURN_IF_ERROR(validate_clip(*clip, *build->skeleton));
    set.clips.push_back(std::move(clip).value());
  }
  // The first mesh node bound to skin 0; its world transform is baked into the vertices.
  int mesh_node = -1;
  for (int n = 0; n < num_nodes && mesh_node < 0; ++n) {
    if (model.nodes[n].skin == 0 && model.nodes[n].mesh >= 0) mesh_node = n;
  }
  glm::mat4 bake(1.0f);
  for (int p = mesh_node; p >= 0; p = parent[p]) {
    Result<Rigid> r = node_rigid(model.nodes[p], path, idx("nodes", p));
    GK_RETURN_IF_ERROR(r);
    bake = to_mat4(*r) * bake;
  }
  Result<std::shared_ptr<const SkinnedMesh>> mesh =
      mesh_node < 0 ? Result<std::shared_ptr<const SkinnedMesh>>(nullptr)
                    : internal::load_skinned_mesh(model, mesh_node, bake, build->joint_of_node,
                                                  build->skeleton->num_joints(), path);
  GK_RETURN_IF_ERROR(mesh);
  if (options.scale_m_per_unit > 0.0f) {
    if (options.scale_m_per_unit != 1.0f) {
      apply_scale(options.scale_m_per_unit, build->skeleton.get(), &set.clips, &*mesh);
    }
    set.scale_m_per_unit = options.scale_m_per_unit;
    set.scale_reason = "given: " + std::to_string(options.scale_m_per_unit) + " m per unit";
  } else {
    // glTF is metres by specification, but exporters write centimetres (or inches) often enough:
    // the legs are measured, as for BVH, and a file whose legs are 85 units long is scaled.
    std::string why;
    const float s = detect_unit_scale(*build->skeleton, &why);
    if (s != 1.0f) {
      apply_scale(s, build->skeleton.get(), &set.clips, &*mesh);
      set.scale_m_per_unit = s;
      set.scale_reason = why + "; glTF says metres";
    } else {
      set.scale_reason = "glTF: metres by specification; " + why;
    }
  }
  set.mesh = *mesh;
  set.skeleton = build->skeleton;
  if (std::string moved = attach_ik_feet(&set); !moved.empty()) {
    set.rig_reason = "IK-style feet attached to the legs: " + moved;
    GK_RETURN_IF_ERROR(validate_skeleton(*set.skeleton, path));
  }
  return set;
}

}  // namespace

Result<ClipSet> load_gltf(const std::string& path, const LoadOptions& options) {
  GK_RETURN_IF_ERROR(check_input_file(path, "glTF file"));
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string err, warn;
  const std::string ext = lower_ascii(path.size() >= 4 ? path.substr(path.size() - 4) : "");
  const bool ok = ext == ".glb" ? loader.LoadBinaryFromFile(&model, &err, &warn, path)
                                : loader.LoadASCIIFromFile(&model, &err, &warn, path);
  if (!ok) return tinygltf_error(path, err);
  return clips_from_model(model, path, options);
}

Result<ClipSet> parse_gltf(std::string_view bytes, const std::string& source_name,
                           const LoadOptions& options) {
  // tinygltf takes an unsigned int length.
  if (bytes.size() > std::numeric_limits<uint32_t>::max()) {
    return Status::Error(source_name + ": larger than 4 GiB, expected a glTF or GLB file");
  }
  const size_t slash = source_name.find_last_of('/');
  const std::string base_dir = slash == std::string::npos ? "" : source_name.substr(0, slash);
  const auto length = static_cast<unsigned int>(bytes.size());
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string err, warn;
  const bool ok =
      bytes.starts_with("glTF")
          ? loader.LoadBinaryFromMemory(&model, &err, &warn,
                                        reinterpret_cast<const unsigned char*>(bytes.data()),
                                        length, base_dir)
          : loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(), length, base_dir);
  if (!ok) return tinygltf_error(source_name, err);
  return clips_from_model(model, source_name, options);
}

}  // namespace gk
