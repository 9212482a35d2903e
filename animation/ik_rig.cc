// Rebuilding an IK-style rig (feet hanging from the root) as ordinary leg chains, keeping every
// joint's model-space transform on every frame.

#include "animation/ik_rig.h"

#include <algorithm>
#include <functional>
#include <memory>
#include <queue>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "animation/mesh.h"

namespace gk {
namespace {

struct Rigid {
  glm::vec3 t{0.0f};
  glm::quat r{1.0f, 0.0f, 0.0f, 0.0f};
};

bool below(const std::vector<int>& parent, int joint, int ancestor) {
  for (int j = parent[joint]; j >= 0; j = parent[j]) {
    if (j == ancestor) return true;
  }
  return false;
}

// Model-space transforms of one local pose on the original hierarchy.
void model_of(const Skeleton& s, const glm::quat* r, const glm::vec3* t, std::vector<Rigid>* out) {
  for (int j = 0; j < s.num_joints(); ++j) {
    const int p = s.parents[j];
    Rigid& m = (*out)[j];
    m.r = p < 0 ? r[j] : (*out)[p].r * r[j];
    m.t = p < 0 ? t[j] : (*out)[p].t + (*out)[p].r * t[j];
  }
}

// `joint`'s transform relative to `parent` (both model space).
Rigid relative(const Rigid& parent, const Rigid& joint) {
  const glm::quat inv = glm::inverse(parent.r);
  return {inv * (joint.t - parent.t), glm::normalize(inv * joint.r)};
}

}  // namespace

std::string attach_ik_feet(ClipSet* set) {
  const Skeleton& old = *set->skeleton;
  const int n = old.num_joints();
  std::vector<int> parent(old.parents.begin(), old.parents.end());
  std::vector<char> moved(n, 0);
  std::string what;
  auto attach = [&](int joint, int under) {
    if (joint < 0 || under < 0 || joint == under || below(parent, joint, under) ||
        below(parent, under, joint)) {
      return;  // already a chain, or attaching would make a cycle (left to the role checks)
    }
    what += (what.empty() ? "" : ", ") + old.names[joint] + " under " + old.names[under] +
            " (was under " + (parent[joint] < 0 ? "nothing" : old.names[parent[joint]]) + ")";
    parent[joint] = under;
    moved[joint] = 1;
  };
  for (Side side : {Side::kLeft, Side::kRight}) {
    attach(old.ankle(side), old.knee(side));
    attach(old.toe(side), old.ankle(side));
  }
  if (what.empty()) return what;

  // Parents first, otherwise in the original order: the smallest index whose parent is placed
  // (Kahn's order on a min-heap; the identity for joints already in order).
  std::vector<std::vector<int>> children(n);
  std::priority_queue<int, std::vector<int>, std::greater<int>> ready;
  for (int j = 0; j < n; ++j) {
    if (parent[j] < 0) {
      ready.push(j);
    } else {
      children[parent[j]].push_back(j);
    }
  }
  std::vector<int> order;  // new index -> old index
  std::vector<int> new_of_old(n, -1);
  while (!ready.empty()) {
    const int j = ready.top();
    ready.pop();
    new_of_old[j] = static_cast<int>(order.size());
    order.push_back(j);
    for (int c : children[j]) ready.push(c);
  }
  // Locals on the new hierarchy: the moved joints' from the model-space pose, the others as they
  // were (their parents keep their model transforms).
  std::vector<Rigid> model(n);
  auto relink = [&](const glm::quat* r, const glm::vec3* t, glm::quat* out_r, glm::vec3* out_t) {
    model_of(old, r, t, &model);
    for (int k = 0; k < n; ++k) {
      const int j = order[k];
      if (moved[j]) {
        const Rigid local = relative(model[parent[j]], model[j]);
        out_r[k] = local.r;
        out_t[k] = local.t;
      } else {
        out_r[k] = r[j];
        out_t[k] = t[j];
      }
    }
  };

  auto s = std::make_shared<Skeleton>();
  s->rest_rotations.resize(n);
  s->rest_translations.resize(n);
  relink(old.rest_rotations.data(), old.rest_translations.data(), s->rest_rotations.data(),
         s->rest_translations.data());
  for (int k = 0; k < n; ++k) {
    const int j = order[k];
    s->names.push_back(old.names[j]);
    s->parents.push_back(static_cast<int16_t>(parent[j] < 0 ? -1 : new_of_old[parent[j]]));
    if (old.end_sites.size() == static_cast<size_t>(n)) s->end_sites.push_back(old.end_sites[j]);
  }
  for (int r = 0; r < kNumJointRoles; ++r) {
    s->roles[r] = static_cast<int16_t>(old.roles[r] < 0 ? -1 : new_of_old[old.roles[r]]);
  }
  for (int16_t j : old.spine_chain) s->spine_chain.push_back(static_cast<int16_t>(new_of_old[j]));

  for (Clip& c : set->clips) {
    std::vector<glm::quat> rot(c.rotations.size());
    std::vector<glm::vec3> trans(c.translations.size());
    for (int f = 0; f < c.num_frames; ++f) {
      const size_t o = static_cast<size_t>(f) * n;
      relink(c.frame_rotations(f), c.frame_translations(f), rot.data() + o, trans.data() + o);
    }
    c.rotations = std::move(rot);
    c.translations = std::move(trans);
  }
  if (set->mesh) {
    auto mesh = std::make_shared<SkinnedMesh>(*set->mesh);
    for (glm::u16vec4& v : mesh->joints) {
      for (int c = 0; c < 4; ++c) v[c] = static_cast<uint16_t>(new_of_old[v[c]]);
    }
    if (mesh->inverse_bind.size() == static_cast<size_t>(n)) {
      for (int k = 0; k < n; ++k) mesh->inverse_bind[k] = set->mesh->inverse_bind[order[k]];
    }
    set->mesh = std::move(mesh);
  }
  set->skeleton = std::move(s);
  return what;
}

std::string add_end_site_toes(ClipSet* set) {
  if (!set || !set->skeleton || set->mesh) return "";
  const Skeleton& old = *set->skeleton;
  const int n = old.num_joints();
  if (old.end_sites.size() != static_cast<size_t>(n)) return "";
  constexpr float kMinFoot = 0.02f;  // [m] an End Site this close to the ankle is no foot
  std::vector<Side> feet;
  for (Side sd : {Side::kLeft, Side::kRight}) {
    const int ankle = old.ankle(sd);
    if (ankle < 0 || old.toe(sd) >= 0) continue;
    const bool leaf = std::find(old.parents.begin(), old.parents.end(), ankle) == old.parents.end();
    if (leaf && glm::length(old.end_sites[ankle]) >= kMinFoot) feet.push_back(sd);
  }
  if (feet.empty()) return "";
  auto s = std::make_shared<Skeleton>(old);
  std::string done;
  std::vector<glm::vec3> offsets;
  for (Side sd : feet) {
    const int ankle = old.ankle(sd);
    std::string name = old.names[ankle] + "_tip";
    while (std::find(s->names.begin(), s->names.end(), name) != s->names.end()) name += "_";
    s->names.push_back(name);
    s->parents.push_back(static_cast<int16_t>(ankle));
    s->rest_translations.push_back(old.end_sites[ankle]);
    s->rest_rotations.push_back(glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
    s->end_sites[ankle] = glm::vec3(0.0f);  // the bone now ends at its toe joint
    s->end_sites.push_back(glm::vec3(0.0f));
    const int toe = s->num_joints() - 1;
    s->roles[static_cast<int>(sd == Side::kLeft ? JointRole::kLeftToe : JointRole::kRightToe)] =
        static_cast<int16_t>(toe);
    offsets.push_back(old.end_sites[ankle]);
    done += (done.empty() ? "" : ", ") + name + " at the End Site of " + old.names[ankle];
  }
  const int m = s->num_joints();
  for (Clip& c : set->clips) {
    std::vector<glm::quat> rot;
    std::vector<glm::vec3> trans;
    rot.reserve(static_cast<size_t>(c.num_frames) * m);
    trans.reserve(static_cast<size_t>(c.num_frames) * m);
    for (int f = 0; f < c.num_frames; ++f) {
      rot.insert(rot.end(), c.frame_rotations(f), c.frame_rotations(f) + n);
      trans.insert(trans.end(), c.frame_translations(f), c.frame_translations(f) + n);
      for (const glm::vec3& o : offsets) {
        rot.emplace_back(1.0f, 0.0f, 0.0f, 0.0f);
        trans.push_back(o);
      }
    }
    c.rotations = std::move(rot);
    c.translations = std::move(trans);
    c.num_joints = m;
  }
  set->skeleton = std::move(s);
  return done;
}

}  // namespace gk
