// The IK-style rig fixture: the built-in character and clips written as a GLB whose feet hang
// from a root joint, the GLB assembled here (JSON chunk + binary chunk, one buffer view per
// accessor) so that the loader is tested against bytes it did not write.

#include "tests/ik_rig_fixture.h"

#include <cstdint>
#include <cstdio>
#include <fstream>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <nlohmann/json.hpp>

#include "animation/mesh.h"
#include "animation/procedural.h"

namespace gk::test {
namespace {

using nlohmann::json;

constexpr int kFloat = 5126, kUnsignedShort = 5123, kUnsignedInt = 5125;

struct Rigid {
  glm::vec3 t{0.0f};
  glm::quat r{1.0f, 0.0f, 0.0f, 0.0f};
};

std::vector<Rigid> forward(const Skeleton& s, const glm::quat* r, const glm::vec3* t) {
  std::vector<Rigid> m(s.num_joints());
  for (int j = 0; j < s.num_joints(); ++j) {
    const int p = s.parents[j];
    m[j].r = p < 0 ? r[j] : m[p].r * r[j];
    m[j].t = p < 0 ? t[j] : m[p].t + m[p].r * t[j];
  }
  return m;
}

Rigid relative(const Rigid& parent, const Rigid& joint) {
  const glm::quat inv = glm::inverse(parent.r);
  return {inv * (joint.t - parent.t), glm::normalize(inv * joint.r)};
}

// Unreal-style names of the built-in joints.
constexpr std::pair<const char*, const char*> kKnownNames[] = {{"Hips", "pelvis"},
                                                               {"Spine", "spine_01"},
                                                               {"Spine1", "spine_02"},
                                                               {"Spine2", "spine_03"},
                                                               {"Neck", "neck_01"},
                                                               {"Head", "head"},
                                                               {"HeadTop_End", "head_end"},
                                                               {"LeftShoulder", "clavicle_l"},
                                                               {"LeftArm", "upperarm_l"},
                                                               {"LeftForeArm", "lowerarm_l"},
                                                               {"LeftHand", "hand_l"},
                                                               {"LeftHandMiddle1", "middle_01_l"},
                                                               {"RightShoulder", "clavicle_r"},
                                                               {"RightArm", "upperarm_r"},
                                                               {"RightForeArm", "lowerarm_r"},
                                                               {"RightHand", "hand_r"},
                                                               {"RightHandMiddle1", "middle_01_r"},
                                                               {"LeftUpLeg", "thigh_l"},
                                                               {"LeftLeg", "calf_l"},
                                                               {"LeftFoot", "foot_l"},
                                                               {"LeftToeBase", "ball_l"},
                                                               {"RightUpLeg", "thigh_r"},
                                                               {"RightLeg", "calf_r"},
                                                               {"RightFoot", "foot_r"},
                                                               {"RightToeBase", "ball_r"}};

std::string le32(uint32_t v) {
  return {static_cast<char>(v & 255), static_cast<char>(v >> 8 & 255),
          static_cast<char>(v >> 16 & 255), static_cast<char>(v >> 24)};
}

class GlbWriter {
 public:
  json doc = {{"asset", {{"version", "2.0"}, {"generator", "gaitkeeper tests"}}},
              {"bufferViews", json::array()},
              {"accessors", json::array()}};

  template <typename T>
  int add(const std::vector<T>& values, size_t count, int component_type, const char* type,
          const json& extra = json::object()) {
    while (bin_.size() % 4 != 0) bin_.push_back('\0');
    const size_t offset = bin_.size(), bytes = values.size() * sizeof(T);
    bin_.append(reinterpret_cast<const char*>(values.data()), bytes);
    doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}});
    json acc = {{"bufferView", doc["bufferViews"].size() - 1},
                {"componentType", component_type},
                {"count", count},
                {"type", type}};
    for (const auto& [k, v] : extra.items()) acc[k] = v;
    doc["accessors"].push_back(acc);
    return static_cast<int>(doc["accessors"].size()) - 1;
  }

  std::string finish() {
    while (bin_.size() % 4 != 0) bin_.push_back('\0');
    doc["buffers"] = json::array({{{"byteLength", bin_.size()}}});
    std::string js = doc.dump();
    while (js.size() % 4 != 0) js.push_back(' ');
    const auto total = static_cast<uint32_t>(12 + 8 + js.size() + 8 + bin_.size());
    return "glTF" + le32(2) + le32(total) + le32(static_cast<uint32_t>(js.size())) + "JSON" + js +
           le32(static_cast<uint32_t>(bin_.size())) + std::string("BIN\0", 4) + bin_;
  }

 private:
  std::string bin_;
};

json vec_json(const glm::vec3& v) { return {v.x, v.y, v.z}; }
json quat_json(const glm::quat& q) { return {q.x, q.y, q.z, q.w}; }

}  // namespace

bool write_file(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return static_cast<bool>(out);
}

IkRig make_ik_rig(const IkRigOptions& o) {
  IkRig rig;
  const ClipSet builtin = make_builtin_clip_set();
  const Skeleton& hs = *builtin.skeleton;
  const int nh = hs.num_joints(), num_nodes = nh + 1;  // node 0: root; node j + 1: joint j
  rig.authored.skeleton = builtin.skeleton;
  rig.authored.mesh = builtin.mesh;
  rig.authored.source = "builtin";
  for (const std::string& name : o.clips) {
    for (const Clip& c : builtin.clips) {
      if (c.name == name) rig.authored.clips.push_back(c);
    }
  }
  std::vector<std::string> node_names(num_nodes);
  node_names[0] = o.known_names ? "root" : "bone_00";
  for (int j = 0; j < nh; ++j) {
    char buf[24];
    std::snprintf(buf, sizeof(buf), "bone_%02d", j + 1);
    std::string name = buf;
    if (o.known_names) {
      for (const auto& [from, to] : kKnownNames) {
        if (hs.names[j] == from) name = to;
      }
    }
    node_names[j + 1] = name;
    rig.names.push_back(name);
  }
  // Hips and feet (and toes) hang from the root.
  auto on_root = [&](int j) {
    return j == hs.role(JointRole::kHips) ||
           (o.feet_under_root && (j == hs.ankle(Side::kLeft) || j == hs.ankle(Side::kRight))) ||
           (o.toes_under_root && (j == hs.toe(Side::kLeft) || j == hs.toe(Side::kRight)));
  };
  std::vector<int> parent_node(num_nodes, -1);
  for (int j = 0; j < nh; ++j) parent_node[j + 1] = on_root(j) ? 0 : hs.parents[j] + 1;
  const float u = o.units_per_m;
  // Node locals in file units from a built-in pose (its locals and model transforms) and the
  // root's model transform; nodes_model receives every node's model transform in file units.
  auto node_locals = [&](const glm::quat* r, const glm::vec3* t, const Rigid& root,
                         std::vector<Rigid>* locals, std::vector<Rigid>* nodes_model) {
    const std::vector<Rigid> model = forward(hs, r, t);
    (*locals)[0] = {root.t * u, root.r};
    if (nodes_model) (*nodes_model)[0] = (*locals)[0];
    for (int j = 0; j < nh; ++j) {
      const Rigid rel = on_root(j) ? relative(root, model[j]) : Rigid{t[j], r[j]};
      (*locals)[j + 1] = {rel.t * u, rel.r};
      if (nodes_model) (*nodes_model)[j + 1] = {model[j].t * u, model[j].r};
    }
  };

  GlbWriter w;
  std::vector<Rigid> rest(num_nodes), rest_model(num_nodes);
  node_locals(hs.rest_rotations.data(), hs.rest_translations.data(), Rigid{}, &rest, &rest_model);
  json nodes = json::array();
  for (int n = 0; n < num_nodes; ++n) {
    json node = {{"name", node_names[n]},
                 {"translation", vec_json(rest[n].t)},
                 {"rotation", quat_json(rest[n].r)}};
    json children = json::array();
    for (int c = 0; c < num_nodes; ++c) {
      if (parent_node[c] == n) children.push_back(c);
    }
    if (!children.empty()) node["children"] = children;
    nodes.push_back(node);
  }
  nodes.push_back({{"name", "body"}, {"mesh", 0}, {"skin", 0}});
  w.doc["nodes"] = nodes;
  w.doc["scenes"] = json::array({{{"nodes", {0, num_nodes}}}});
  w.doc["scene"] = 0;

  // The skin lists the joints in reverse (children first): the loader must sort them.
  std::vector<int> skin_joints, skin_of_node(num_nodes);
  for (int n = num_nodes - 1; n >= 0; --n) {
    skin_of_node[n] = static_cast<int>(skin_joints.size());
    skin_joints.push_back(n);
  }
  std::vector<float> ibm;
  for (int n : skin_joints) {
    const glm::mat4 m =
        glm::translate(glm::mat4(1.0f), rest_model[n].t) * glm::mat4_cast(rest_model[n].r);
    const glm::mat4 inv = glm::inverse(m);
    ibm.insert(ibm.end(), glm::value_ptr(inv), glm::value_ptr(inv) + 16);
  }
  w.doc["skins"] =
      json::array({{{"joints", skin_joints},
                    {"inverseBindMatrices", w.add(ibm, skin_joints.size(), kFloat, "MAT4")}}});

  const SkinnedMesh& mesh = *builtin.mesh;
  std::vector<float> pos, nrm, wts;
  std::vector<uint16_t> jts;
  glm::vec3 lo(1e30f), hi(-1e30f);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const glm::vec3 p = mesh.positions[v] * u;
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
    pos.insert(pos.end(), {p.x, p.y, p.z});
    nrm.insert(nrm.end(), {mesh.normals[v].x, mesh.normals[v].y, mesh.normals[v].z});
    for (int c = 0; c < 4; ++c) {
      jts.push_back(static_cast<uint16_t>(skin_of_node[mesh.joints[v][c] + 1]));
      wts.push_back(mesh.weights[v][c]);
    }
  }
  const size_t nv = mesh.positions.size();
  json attributes = {
      {"POSITION", w.add(pos, nv, kFloat, "VEC3", {{"min", vec_json(lo)}, {"max", vec_json(hi)}})},
      {"NORMAL", w.add(nrm, nv, kFloat, "VEC3")},
      {"JOINTS_0", w.add(jts, nv, kUnsignedShort, "VEC4")},
      {"WEIGHTS_0", w.add(wts, nv, kFloat, "VEC4")}};
  w.doc["meshes"] = json::array(
      {{{"primitives", json::array({{{"attributes", attributes},
                                     {"indices", w.add(mesh.indices, mesh.indices.size(),
                                                       kUnsignedInt, "SCALAR")}}})}}});

  // Each clip twice over (two strides) plus the first frame again, moved on by two strides' travel
  // (so that the loader sees a closed loop and drops it).
  json animations = json::array();
  for (const Clip& c : rig.authored.clips) {
    const int n = c.num_frames, hips = hs.role(JointRole::kHips);
    auto hips_at = [&](int f) {
      return forward(hs, c.frame_rotations(f), c.frame_translations(f))[hips].t;
    };
    glm::vec3 stride(0.0f);
    if (n >= 3) stride = 2.0f * hips_at(n - 1) - hips_at(n - 2) - hips_at(0);
    stride.y = 0.0f;
    std::vector<float> times;
    std::vector<std::vector<float>> node_t(num_nodes), node_r(num_nodes);
    std::vector<std::vector<glm::vec3>> clip_positions;
    std::vector<Rigid> locals(num_nodes);
    for (int k = 0; k <= 2 * n; ++k) {
      const int f = k % n;
      std::vector<glm::vec3> t(c.frame_translations(f), c.frame_translations(f) + nh);
      t[hips] += stride * static_cast<float>(k / n);
      const std::vector<Rigid> model = forward(hs, c.frame_rotations(f), t.data());
      Rigid root;
      root.t = glm::vec3(model[hips].t.x, 0.0f, model[hips].t.z);
      node_locals(c.frame_rotations(f), t.data(), root, &locals, nullptr);
      times.push_back(static_cast<float>(k) / c.fps);
      for (int m = 0; m < num_nodes; ++m) {
        node_t[m].insert(node_t[m].end(), {locals[m].t.x, locals[m].t.y, locals[m].t.z});
        node_r[m].insert(node_r[m].end(),
                         {locals[m].r.x, locals[m].r.y, locals[m].r.z, locals[m].r.w});
      }
      if (k < 2 * n) {
        clip_positions.emplace_back();
        for (const Rigid& m : model) clip_positions.back().push_back(m.t);
      }
    }
    rig.positions.push_back(std::move(clip_positions));
    const int input = w.add(times, times.size(), kFloat, "SCALAR",
                            {{"min", {times.front()}}, {"max", {times.back()}}});
    json samplers = json::array(), channels = json::array();
    for (int m = 0; m < num_nodes; ++m) {
      for (const char* path : {"translation", "rotation"}) {
        const bool rot = path[0] == 'r';
        const int output =
            w.add(rot ? node_r[m] : node_t[m], times.size(), kFloat, rot ? "VEC4" : "VEC3");
        channels.push_back(
            {{"sampler", samplers.size()}, {"target", {{"node", m}, {"path", path}}}});
        samplers.push_back({{"input", input}, {"output", output}, {"interpolation", "LINEAR"}});
      }
    }
    animations.push_back({{"name", c.name}, {"samplers", samplers}, {"channels", channels}});
  }
  w.doc["animations"] = animations;
  rig.glb = w.finish();

  json roles = json::object();
  for (JointRole r :
       {JointRole::kHips, JointRole::kChest, JointRole::kLeftHip, JointRole::kLeftKnee,
        JointRole::kLeftAnkle, JointRole::kLeftToe, JointRole::kRightHip, JointRole::kRightKnee,
        JointRole::kRightAnkle, JointRole::kRightToe}) {
    roles[std::string(joint_role_name(r))] = rig.names[hs.role(r)];
  }
  rig.roles_json = json{{"roles", roles}}.dump(2);
  return rig;
}

}  // namespace gk::test
