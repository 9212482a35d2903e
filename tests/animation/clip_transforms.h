#pragma once
// Clips changed in memory the way a clip nobody has seen may differ from the shared ones (frame
// rate, travel direction, root placement, an extra root, the floor, a mirrored body, capture
// jitter): the transforms of the invariance tests (tests/animation/test_invariance.cc and
// tests/mediator/test_library_invariance.cc).

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "animation/clip_library.h"
#include "tests/test_data.h"

namespace gk::test {

inline constexpr float kPi = std::numbers::pi_v<float>;
inline constexpr float kDeg = kPi / 180.0f;

struct Rig {
  std::shared_ptr<Skeleton> sk;
  Clip clip;
};

inline Rig load_rig(const std::string& rel, const std::string& clip_name = "") {
  Result<ClipSet> set = load_clip_file(test::data_path(rel));
  EXPECT_TRUE(set.ok()) << set.message();
  if (!set.ok()) return {};
  Rig r{std::make_shared<Skeleton>(*set->skeleton), set->clips.at(0)};
  for (const Clip& c : set->clips) {
    if (c.name == clip_name) r.clip = c;
  }
  return r;
}

// --- Transforms -----------------------------------------------------------------------------

// Frame k of `out` set to c at fractional frame f: rotations slerped, translations lerped between
// the frames around it (a loop's last frame runs on into its first; a take's end is held).
inline void sample_frame(const Clip& c, float f, Clip* out, int k) {
  const int n = c.num_frames;
  int i0, i1;
  if (c.loops) {
    f -= std::floor(f / static_cast<float>(n)) * static_cast<float>(n);
    i0 = std::min(static_cast<int>(f), n - 1);
    i1 = (i0 + 1) % n;
  } else {
    f = std::clamp(f, 0.0f, static_cast<float>(n - 1));
    i0 = std::min(static_cast<int>(f), std::max(n - 2, 0));
    i1 = std::min(i0 + 1, n - 1);
  }
  const float u = f - static_cast<float>(i0);
  const int nj = c.num_joints;
  for (int j = 0; j < nj; ++j) {
    const size_t o = static_cast<size_t>(k) * nj + j;
    out->rotations[o] = glm::slerp(c.frame_rotations(i0)[j], c.frame_rotations(i1)[j], u);
    out->translations[o] = glm::mix(c.frame_translations(i0)[j], c.frame_translations(i1)[j], u);
  }
}

// The take resampled at `fps` (translations lerped, rotations slerped between frames).
inline Clip resampled(const Clip& c, float fps) {
  Clip out = c;
  out.fps = fps;
  const float span_s = (c.num_frames - 1) / c.fps;
  out.num_frames = static_cast<int>(std::floor(span_s * fps + 1e-4f)) + 1;
  out.rotations.resize(static_cast<size_t>(out.num_frames) * c.num_joints);
  out.translations.resize(out.rotations.size());
  for (int k = 0; k < out.num_frames; ++k) sample_frame(c, k / fps * c.fps, &out, k);
  return out;
}

// A loop retimed smoothly, so that one part of it plays slower and the rest faster (by up to
// `amount` of the mean pace, < 1), its frame count and duration kept and the loop still closed:
// a walk whose two steps then differ in length, as a capture's may.
inline Clip unevenly_timed(const Clip& loop, float amount) {
  Clip out = loop;
  const float n = static_cast<float>(loop.num_frames);
  // Frame k shows the loop at frame s(k) = n (x + a/2pi (sin(2pi x + 1) - sin 1)), x = k / n:
  // s' = n (1 + a cos(2pi x + 1)) > 0 for a < 1, and s(n) = n.
  for (int k = 0; k < loop.num_frames; ++k) {
    const float x = static_cast<float>(k) / n;
    const float s =
        n * (x + amount / (2.0f * kPi) * (std::sin(2.0f * kPi * x + 1.0f) - std::sin(1.0f)));
    sample_frame(loop, s, &out, k);
  }
  return out;
}

// The whole take moved rigidly: every root's rotation and translation mapped by (q, d).
inline void move_take(Clip* c, const Skeleton& sk, const glm::quat& q, const glm::vec3& d) {
  for (int f = 0; f < c->num_frames; ++f) {
    for (int j = 0; j < c->num_joints; ++j) {
      if (sk.parents[j] >= 0) continue;
      const size_t o = static_cast<size_t>(f) * c->num_joints + j;
      c->rotations[o] = glm::normalize(q * c->rotations[o]);
      c->translations[o] = q * c->translations[o] + d;
    }
  }
}

// The take as a tool with another up axis would author it: the whole world turned by `up`
// (angleAxis(90 deg, x) takes +y to +z: a Z-up file), rest offsets included, every joint's
// rotation expressed in the turned axes, so every joint's position is `up` times the original's.
inline Rig authored_turned(const Rig& in, const glm::quat& up) {
  auto sk = std::make_shared<Skeleton>(*in.sk);
  const glm::quat inv = glm::inverse(up);
  for (size_t j = 0; j < sk->rest_translations.size(); ++j) {
    sk->rest_translations[j] = up * sk->rest_translations[j];
    sk->rest_rotations[j] = glm::normalize(up * sk->rest_rotations[j] * inv);
    if (j < sk->end_sites.size()) sk->end_sites[j] = up * sk->end_sites[j];
  }
  Rig out{sk, in.clip};
  for (size_t o = 0; o < out.clip.rotations.size(); ++o) {
    out.clip.rotations[o] = glm::normalize(up * out.clip.rotations[o] * inv);
    out.clip.translations[o] = up * out.clip.translations[o];
  }
  return out;
}

// The root raised by `rise_m` * (frame / last frame): a floor that drifts up over the take.
inline void raise_over_take(Clip* c, float rise_m) {
  for (int f = 0; f < c->num_frames; ++f) {
    c->translations[static_cast<size_t>(f) * c->num_joints].y +=
        rise_m * f / std::max(1, c->num_frames - 1);
  }
}

// A new root joint above the old one, at `offset` and turned by `rot` (a Z-up armature); the old
// root is re-expressed in it so that the body is where it was, moved by `offset`.
inline Rig with_parent_root(const Rig& in, const glm::vec3& offset, const glm::quat& rot) {
  const Skeleton& s = *in.sk;
  auto sk = std::make_shared<Skeleton>();
  sk->names.push_back("Armature");
  sk->parents.push_back(-1);
  sk->rest_translations.push_back(offset);
  sk->rest_rotations.push_back(rot);
  sk->end_sites.push_back(glm::vec3(0.0f));
  const glm::quat inv = glm::inverse(rot);
  for (int j = 0; j < s.num_joints(); ++j) {
    sk->names.push_back(s.names[j]);
    sk->parents.push_back(static_cast<int16_t>(s.parents[j] + 1));
    const bool root = s.parents[j] < 0;
    sk->rest_translations.push_back(root ? inv * s.rest_translations[j] : s.rest_translations[j]);
    sk->rest_rotations.push_back(root ? inv * s.rest_rotations[j] : s.rest_rotations[j]);
    sk->end_sites.push_back(j < static_cast<int>(s.end_sites.size()) ? s.end_sites[j]
                                                                     : glm::vec3(0.0f));
  }
  detect_joint_roles(sk.get());
  Rig out{sk, in.clip};
  const int nj = s.num_joints() + 1;
  out.clip.num_joints = nj;
  out.clip.rotations.clear();
  out.clip.translations.clear();
  for (int f = 0; f < in.clip.num_frames; ++f) {
    out.clip.rotations.push_back(rot);
    out.clip.translations.push_back(offset);
    for (int j = 0; j < s.num_joints(); ++j) {
      const bool root = s.parents[j] < 0;
      const glm::quat r = in.clip.frame_rotations(f)[j];
      const glm::vec3 t = in.clip.frame_translations(f)[j];
      out.clip.rotations.push_back(root ? inv * r : r);
      out.clip.translations.push_back(root ? inv * t : t);
    }
  }
  return out;
}

// The name of the other side's joint ("LeftUpLeg" -> "RightUpLeg", "lfemur" -> "rfemur",
// "DEF-thigh.L" -> "DEF-thigh.R"), if the skeleton has it; else the name itself.
inline std::string other_side(const Skeleton& sk, const std::string& name) {
  const std::pair<std::string, std::string> swaps[] = {
      {"Left", "Right"}, {"left", "right"}, {".L", ".R"}, {"_L", "_R"}, {"_l", "_r"}};
  for (const auto& [a, b] : swaps) {
    for (const auto& [from, to] : {std::pair{a, b}, std::pair{b, a}}) {
      const size_t p = name.find(from);
      if (p == std::string::npos) continue;
      std::string cand = name;
      cand.replace(p, from.size(), to);
      if (sk.find(cand) >= 0) return cand;
    }
  }
  for (const auto& [from, to] :
       {std::pair{'l', 'r'}, std::pair{'r', 'l'}, std::pair{'L', 'R'}, std::pair{'R', 'L'}}) {
    if (!name.empty() && name[0] == from) {
      const std::string cand = to + name.substr(1);
      if (sk.find(cand) >= 0) return cand;
    }
  }
  return name;
}

// The mirror image across the x = 0 plane: every translation's x negated, every rotation
// reflected, and each joint given its other-side name, so the left leg is again at +x.
inline Rig mirrored(const Rig& in) {
  auto sk = std::make_shared<Skeleton>(*in.sk);
  auto reflect_t = [](glm::vec3 t) { return glm::vec3(-t.x, t.y, t.z); };
  auto reflect_q = [](glm::quat q) { return glm::quat(q.w, q.x, -q.y, -q.z); };
  for (int j = 0; j < sk->num_joints(); ++j) {
    sk->names[j] = other_side(*in.sk, in.sk->names[j]);
    sk->rest_translations[j] = reflect_t(sk->rest_translations[j]);
    sk->rest_rotations[j] = reflect_q(sk->rest_rotations[j]);
    if (j < static_cast<int>(sk->end_sites.size())) sk->end_sites[j] = reflect_t(sk->end_sites[j]);
  }
  detect_joint_roles(sk.get());
  Rig out{sk, in.clip};
  for (glm::vec3& t : out.clip.translations) t = reflect_t(t);
  for (glm::quat& q : out.clip.rotations) q = reflect_q(q);
  return out;
}

// Capture jitter, seeded: Gaussian noise of `root_mm` on the root's position and a rotation of
// `deg` (standard deviation, about a random axis) on every joint, on every frame.
inline Clip jittered(const Clip& c, uint32_t seed, float root_mm, float deg) {
  Clip out = c;
  std::mt19937 rng(seed);
  std::normal_distribution<float> gauss(0.0f, 1.0f);
  for (int f = 0; f < c.num_frames; ++f) {
    for (int j = 0; j < c.num_joints; ++j) {
      const size_t o = static_cast<size_t>(f) * c.num_joints + j;
      glm::vec3 axis(gauss(rng), gauss(rng), gauss(rng));
      axis = glm::length(axis) > 1e-6f ? glm::normalize(axis) : glm::vec3(0, 1, 0);
      out.rotations[o] =
          glm::normalize(glm::angleAxis(deg * kDeg * gauss(rng), axis) * c.rotations[o]);
      if (j == 0) {
        out.translations[o] += 0.001f * root_mm * glm::vec3(gauss(rng), gauss(rng), gauss(rng));
      }
    }
  }
  return out;
}

}  // namespace gk::test
