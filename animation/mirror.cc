#include "animation/mirror.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>

#include "animation/pose_jobs.h"

namespace gk {
namespace {

// Rest pose positions and orientations (model space) and the plane the body is mirrored in at rest: through the
// hips' middle, normal along the right-to-left hip line.
struct RestFrame {
  std::vector<glm::vec3> position;
  std::vector<glm::quat> rotation;
  glm::vec3 centre{0.0f};
  glm::vec3 normal{1.0f, 0.0f, 0.0f};
  float leg_m = 1.0f;
  std::vector<int> depth;
};

RestFrame rest_frame(const Skeleton& sk) {
  const int nj = sk.num_joints();
  std::vector<glm::mat4> model(static_cast<size_t>(nj));
  LocalToModelJob{&sk, sk.rest_rotations, sk.rest_translations, glm::mat4(1.0f), model}.run();
  RestFrame r;
  for (const glm::mat4& m : model) {
    r.position.push_back(translation_of(m));
    r.rotation.push_back(glm::normalize(glm::quat_cast(glm::mat3(m))));
  }
  r.depth.assign(static_cast<size_t>(nj), 0);
  for (int j = 0; j < nj; ++j) {
    if (sk.parents[j] >= 0) r.depth[j] = r.depth[sk.parents[j]] + 1;
  }
  const int hl = sk.hip(Side::kLeft), hr = sk.hip(Side::kRight);
  if (hl >= 0 && hr >= 0) {
    const glm::vec3 across = r.position[hl] - r.position[hr];
    if (glm::length(across) > 1e-6f) {
      r.centre = 0.5f * (r.position[hl] + r.position[hr]);
      r.normal = glm::normalize(across);
    }
    const int al = sk.ankle(Side::kLeft);
    if (al >= 0) r.leg_m = std::max(1e-3f, glm::length(r.position[hl] - r.position[al]));
  }
  return r;
}

glm::vec3 reflect_point(const glm::vec3& p, const glm::vec3& point, const glm::vec3& n) {
  return p - 2.0f * glm::dot(p - point, n) * n;
}

// A rotation seen in the mirror: about the reflected axis, the other way round.
glm::quat reflect_rotation(const glm::quat& q, const glm::vec3& n) {
  const glm::vec3 v(q.x, q.y, q.z);
  const glm::vec3 r = 2.0f * glm::dot(v, n) * n - v;
  return glm::quat(q.w, r.x, r.y, r.z);
}

// Names that differ from `name` only in one side marker: Left/Right (any case) or a single
// L/R/l/r letter.
std::vector<std::string> side_swapped_names(const std::string& name) {
  std::vector<std::string> out;
  const std::pair<const char*, const char*> words[] = {
      {"Left", "Right"}, {"left", "right"}, {"LEFT", "RIGHT"}};
  for (const auto& [a, b] : words) {
    for (const auto& [from, to] : {std::pair{a, b}, std::pair{b, a}}) {
      const std::string f(from);
      for (size_t at = name.find(f); at != std::string::npos; at = name.find(f, at + 1)) {
        std::string s = name;
        s.replace(at, f.size(), to);
        out.push_back(std::move(s));
      }
    }
  }
  for (size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    const char swapped = c == 'L' ? 'R' : c == 'R' ? 'L' : c == 'l' ? 'r' : c == 'r' ? 'l' : 0;
    if (swapped == 0) continue;
    std::string s = name;
    s[i] = swapped;
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace

std::vector<int16_t> mirror_joint_map(const Skeleton& sk) {
  const int nj = sk.num_joints();
  std::vector<int16_t> map(static_cast<size_t>(nj), -1);
  if (nj == 0) return map;
  const RestFrame rest = rest_frame(sk);
  auto pair = [&](int a, int b) {
    if (a < 0 || b < 0 || a == b || map[a] >= 0 || map[b] >= 0) return;
    map[a] = static_cast<int16_t>(b);
    map[b] = static_cast<int16_t>(a);
  };
  // How far joint b is from where the mirror puts joint a at rest [m].
  auto mismatch = [&](int a, int b) {
    return glm::length(rest.position[b] -
                       reflect_point(rest.position[a], rest.centre, rest.normal));
  };
  // 1. The roles: the legs and shoulders are known on both sides.
  const JointRole left[] = {JointRole::kLeftHip, JointRole::kLeftKnee, JointRole::kLeftAnkle,
                            JointRole::kLeftToe, JointRole::kLeftShoulder};
  const JointRole right[] = {JointRole::kRightHip, JointRole::kRightKnee, JointRole::kRightAnkle,
                             JointRole::kRightToe, JointRole::kRightShoulder};
  for (size_t i = 0; i < std::size(left); ++i) pair(sk.role(left[i]), sk.role(right[i]));
  // 2. Names that differ only in their side, where the rest pose agrees (a quarter of the leg:
  //    rigs are not exactly symmetric, but a wrong pair is far off).
  const float name_tol = 0.25f * rest.leg_m;
  for (int j = 0; j < nj; ++j) {
    if (map[j] >= 0) continue;
    int best = -1;
    float best_d = name_tol;
    for (const std::string& candidate : side_swapped_names(sk.names[j])) {
      const int k = sk.find(candidate);
      if (k < 0 || k == j || map[k] >= 0) continue;
      const float d = mismatch(j, k);
      if (d <= best_d) {
        best = k;
        best_d = d;
      }
    }
    pair(j, best);
  }
  // 3. The rest pose alone, for joints off the middle plane whose names tell nothing: the joint at
  //    the same depth that lies where the mirror puts it (a twentieth of the leg).
  const float geo_tol = 0.05f * rest.leg_m;
  for (int j = 0; j < nj; ++j) {
    if (map[j] >= 0) continue;
    if (std::abs(glm::dot(rest.position[j] - rest.centre, rest.normal)) <= geo_tol) continue;
    int best = -1;
    float best_d = geo_tol;
    for (int k = 0; k < nj; ++k) {
      if (k == j || map[k] >= 0 || rest.depth[k] != rest.depth[j]) continue;
      const float d = mismatch(j, k);
      if (d <= best_d) {
        best = k;
        best_d = d;
      }
    }
    pair(j, best);
  }
  for (int j = 0; j < nj; ++j) {
    if (map[j] < 0) map[j] = static_cast<int16_t>(j);
  }
  return map;
}

Clip mirror_clip(const Clip& clip, const Skeleton& sk, const std::vector<int16_t>& map,
                 const glm::vec3& point, const glm::vec3& normal) {
  const int nj = sk.num_joints();
  Clip out = clip;
  if (clip.num_joints != nj || static_cast<int>(map.size()) != nj || nj == 0) return out;
  const glm::vec3 n = glm::length(normal) > 1e-6f ? glm::normalize(normal) : glm::vec3(1, 0, 0);
  const RestFrame rf = rest_frame(sk);
  const std::vector<glm::quat>& rest_q = rf.rotation;
  // The rest pose is symmetric about the body's own middle plane (normal n0 in model space), so a
  // joint's turn away from rest is mirrored there; the reflection asked for is that one followed
  // by the rotation taking one plane onto the other (two reflections make a rotation) and a shift.
  const glm::vec3 n0 = rf.normal;
  const glm::mat3 reflect_n = glm::mat3(1.0f) - 2.0f * glm::outerProduct(n, n);
  const glm::mat3 reflect_n0 = glm::mat3(1.0f) - 2.0f * glm::outerProduct(n0, n0);
  const glm::mat3 turn_m = reflect_n * reflect_n0;
  const glm::quat turn = glm::normalize(glm::quat_cast(turn_m));
  const glm::vec3 shift = 2.0f * glm::dot(point, n) * n;
  // Joints whose offset from their parent the clip animates (a root's travel, a rig with position
  // channels everywhere) are placed where the reflection puts them; the others keep their bones.
  std::vector<uint8_t> moves(static_cast<size_t>(nj), 0);
  for (int j = 0; j < nj; ++j) {
    moves[j] = sk.parents[j] < 0;
    for (int f = 1; f < clip.num_frames && !moves[j]; ++f) {
      const glm::vec3 d = clip.translations[static_cast<size_t>(f) * nj + j] - clip.translations[j];
      moves[j] = glm::dot(d, d) > 1e-10f;
    }
  }
  std::vector<glm::mat4> model(static_cast<size_t>(nj));
  std::vector<glm::quat> q(static_cast<size_t>(nj));
  std::vector<glm::vec3> p(static_cast<size_t>(nj));
  for (int f = 0; f < clip.num_frames; ++f) {
    clip_frame_model(clip, sk, f, model);
    for (int j = 0; j < nj; ++j) {
      const int m = map[j];
      const glm::quat posed = glm::normalize(glm::quat_cast(glm::mat3(model[j])));
      // The joint's turn away from its rest orientation, seen in the mirror, on the mirror
      // joint's own rest orientation.
      const glm::quat away = posed * glm::inverse(rest_q[j]);
      q[m] = glm::normalize(turn * (reflect_rotation(away, n0) * rest_q[m]));
      p[m] = turn_m * (reflect_n0 * translation_of(model[j])) + shift;
    }
    glm::quat* rot = out.rotations.data() + static_cast<size_t>(f) * nj;
    glm::vec3* tra = out.translations.data() + static_cast<size_t>(f) * nj;
    for (int k = 0; k < nj; ++k) {
      const int parent = sk.parents[k];
      if (parent < 0) {
        rot[k] = q[k];
        tra[k] = p[k];
      } else {
        const glm::quat inv = glm::inverse(q[parent]);
        rot[k] = glm::normalize(inv * q[k]);
        if (moves[k]) tra[k] = inv * (p[k] - p[parent]);
      }
    }
  }
  return out;
}

}  // namespace gk
