// Clip validation and the loaders' shared helpers (FK for loop detection, file names).

#include "animation/clip.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtx/quaternion.hpp>

#include "animation/loader_internal.h"

namespace gk {

Status validate_clip(const Clip& clip, const Skeleton& skeleton) {
  const std::string where =
      clip.source.empty() ? "clip '" + clip.name + "'" : clip.source + ": clip '" + clip.name + "'";
  auto fail = [&](const std::string& what) { return Status::Error(where + ": " + what); };
  if (!(clip.fps > 0.0f) || !std::isfinite(clip.fps)) return fail("fps must be > 0");
  if (clip.num_frames < 1) return fail("has no frames");
  if (clip.num_joints != skeleton.num_joints()) {
    return fail("has " + std::to_string(clip.num_joints) + " joints, the skeleton has " +
                std::to_string(skeleton.num_joints()));
  }
  const size_t n = static_cast<size_t>(clip.num_frames) * static_cast<size_t>(clip.num_joints);
  if (clip.rotations.size() != n || clip.translations.size() != n) {
    return fail("expected " + std::to_string(n) + " rotations and translations, found " +
                std::to_string(clip.rotations.size()) + " and " +
                std::to_string(clip.translations.size()));
  }
  for (size_t i = 0; i < n; ++i) {
    const glm::quat& q = clip.rotations[i];
    const glm::vec3& t = clip.translations[i];
    const float len = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    const bool finite_t = std::isfinite(t.x) && std::isfinite(t.y) && std::isfinite(t.z);
    if (!finite_t || !std::isfinite(len) || std::abs(len - 1.0f) > 1e-3f) {
      return fail("frame " + std::to_string(i / clip.num_joints) + ", joint " +
                  std::to_string(i % clip.num_joints) +
                  ": non-finite translation or non-unit rotation");
    }
  }
  return Status::Ok();
}

namespace {

// The slope at a sample between steps a and b (uniform spacing) that keeps a cubic through the
// samples monotone between them (Fritsch and Butland: the harmonic mean of two steps the same
// way, flat at a turn), so it never overshoots a sample: a foot that lands in the capture does not
// dip through the floor and back between two frames.
inline float monotone_slope(float a, float b) {
  return a * b > 0.0f ? 2.0f * a * b / (a + b) : 0.0f;
}

// A monotone cubic Hermite through p0 p1 p2 p3 (uniform spacing) at u in [0, 1] between p1 and
// p2, per component, on differences: a constant track stays exactly constant.
template <class V>
V monotone_cubic(const V& p0, const V& p1, const V& p2, const V& p3, float u) {
  V out = p1;
  for (int c = 0; c < V::length(); ++c) {
    const float d0 = p1[c] - p0[c], d = p2[c] - p1[c], d2 = p3[c] - p2[c];
    const float m1 = monotone_slope(d0, d), m2 = monotone_slope(d, d2);
    out[c] = p1[c] + u * (m1 + u * (3.0f * d - 2.0f * m1 - m2 + u * (m1 + m2 - 2.0f * d)));
  }
  return out;
}

}  // namespace

Clip upsample_clip(const Clip& clip, int factor, const Skeleton& skeleton) {
  const int n = clip.num_frames, J = clip.num_joints;
  if (factor <= 1 || n < 2 || J != skeleton.num_joints()) return clip;
  Clip out = clip;
  out.fps = clip.fps * static_cast<float>(factor);
  out.num_frames = clip.loops ? n * factor : (n - 1) * factor + 1;
  const size_t count = static_cast<size_t>(out.num_frames) * J;
  out.rotations.assign(count, glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
  out.translations.assign(count, glm::vec3(0.0f));
  // A root's ground travel over one loop: the frame after the last is the first moved on by it
  // (an in-place loop's is about zero).
  std::vector<glm::vec3> loop_travel(J, glm::vec3(0.0f));
  if (clip.loops) {
    for (int j = 0; j < J; ++j) {
      if (skeleton.parents[j] >= 0) continue;
      const glm::vec3 d = (clip.frame_translations(n - 1)[j] - clip.frame_translations(0)[j]) *
                          (static_cast<float>(n) / static_cast<float>(n - 1));
      loop_travel[j] = glm::vec3(d.x, 0.0f, d.z);
    }
  }
  // Frame i's sample of joint j, i beyond the ends wrapped (a loop) or extended along the end's
  // own velocity (a take: no kink at its ends).
  auto trans = [&](int i, int j) {
    if (i >= 0 && i < n) return clip.frame_translations(i)[j];
    if (clip.loops) {
      return i < 0 ? clip.frame_translations(i + n)[j] - loop_travel[j]
                   : clip.frame_translations(i - n)[j] + loop_travel[j];
    }
    const int e = i < 0 ? 0 : n - 1, in = i < 0 ? 1 : n - 2;
    return 2.0f * clip.frame_translations(e)[j] - clip.frame_translations(in)[j];
  };
  auto rot = [&](int i, int j) {
    if (i >= 0 && i < n) return clip.frame_rotations(i)[j];
    if (clip.loops) return clip.frame_rotations(((i % n) + n) % n)[j];
    // Mirrored about the end: the end's rotation turned on by its last step (q_e * inv(q_in) *
    // q_e).
    const int e = i < 0 ? 0 : n - 1, in = i < 0 ? 1 : n - 2;
    const glm::quat qe = clip.frame_rotations(e)[j];
    return glm::normalize(qe * glm::inverse(clip.frame_rotations(in)[j]) * qe);
  };
  for (int f = 0; f < out.num_frames; ++f) {
    const int i = f / factor;
    const float u = static_cast<float>(f % factor) / static_cast<float>(factor);
    glm::quat* r_out = out.rotations.data() + static_cast<size_t>(f) * J;
    glm::vec3* t_out = out.translations.data() + static_cast<size_t>(f) * J;
    if (u == 0.0f) {  // a source frame: kept exactly
      const int src = clip.loops ? i % n : i;
      std::copy_n(clip.frame_rotations(src), J, r_out);
      std::copy_n(clip.frame_translations(src), J, t_out);
      continue;
    }
    for (int j = 0; j < J; ++j) {
      t_out[j] = monotone_cubic(trans(i - 1, j), trans(i, j), trans(i + 1, j), trans(i + 2, j), u);
      // The four rotations on the hemisphere of the second (q and -q are one rotation), each
      // component on the monotone cubic, normalised: for samples this dense, close to a
      // spherical curve, and never turned beyond the frames either side.
      const glm::quat q1 = rot(i, j);
      glm::vec4 v[4];
      for (int k = 0; k < 4; ++k) {
        const glm::quat q = k == 1 ? q1 : rot(i - 1 + k, j);
        const float s = glm::dot(q, q1) < 0.0f ? -1.0f : 1.0f;
        v[k] = s * glm::vec4(q.x, q.y, q.z, q.w);
      }
      if (v[0] == v[1] && v[2] == v[1] && v[3] == v[1]) {  // a still joint stays exactly still
        r_out[j] = q1;
        continue;
      }
      const glm::vec4 c = monotone_cubic(v[0], v[1], v[2], v[3], u);
      const float len = glm::length(c);
      r_out[j] = len > 1e-6f ? glm::quat(c.w / len, c.x / len, c.y / len, c.z / len) : q1;
    }
  }
  return out;
}

namespace internal {

void local_to_model(const Skeleton& skeleton, const glm::quat* rotations,
                    const glm::vec3* translations, std::vector<glm::mat4>* out_model) {
  const int n = skeleton.num_joints();
  out_model->resize(n);
  for (int j = 0; j < n; ++j) {
    const glm::mat4 local = glm::translate(glm::mat4(1.0f), translations[j]) *
                            glm::toMat4(glm::normalize(rotations[j]));
    const int p = skeleton.parents[j];
    (*out_model)[j] = p >= 0 ? (*out_model)[p] * local : local;
  }
}

float loop_mismatch_m(const Clip& clip, const Skeleton& skeleton) {
  if (clip.num_frames < 2) return 0.0f;
  const int n = clip.num_joints;
  std::vector<glm::mat4> a, b;
  auto pose = [&](int frame, std::vector<glm::mat4>* out) {
    std::vector<glm::vec3> t(clip.frame_translations(frame), clip.frame_translations(frame) + n);
    for (int j = 0; j < n; ++j) {
      if (skeleton.parents[j] < 0) t[j].x = t[j].z = 0.0f;
    }
    local_to_model(skeleton, clip.frame_rotations(frame), t.data(), out);
  };
  pose(0, &a);
  pose(clip.num_frames - 1, &b);
  // Positions alone miss leaf joints turning in place (a head, a toe), so each joint's axes are
  // compared too, as points kLever from the joint.
  constexpr float kLever = 0.1f;
  float worst = 0.0f;
  for (int j = 0; j < n; ++j) {
    worst = std::max(worst, glm::length(glm::vec3(a[j][3] - b[j][3])));
    for (int axis = 0; axis < 3; ++axis) {
      worst = std::max(worst, kLever * glm::length(glm::vec3(a[j][axis] - b[j][axis])));
    }
  }
  return worst;
}

void finalize_loop(Clip* clip, const Skeleton& skeleton, float tolerance_m) {
  clip->loops = false;
  if (clip->num_frames < 3 || loop_mismatch_m(*clip, skeleton) > tolerance_m) return;
  clip->loops = true;
  clip->num_frames -= 1;
  const size_t keep = static_cast<size_t>(clip->num_frames) * clip->num_joints;
  clip->rotations.resize(keep);
  clip->translations.resize(keep);
}

float loop_tolerance_m(const Skeleton& skeleton) {
  std::vector<glm::mat4> model;
  local_to_model(skeleton, skeleton.rest_rotations.data(), skeleton.rest_translations.data(),
                 &model);
  float leg = 0.0f;
  int sides = 0;
  for (Side s : {Side::kLeft, Side::kRight}) {
    if (skeleton.hip(s) < 0 || skeleton.ankle(s) < 0) continue;
    leg += glm::length(glm::vec3(model[skeleton.hip(s)][3] - model[skeleton.ankle(s)][3]));
    ++sides;
  }
  if (sides == 0 || !(leg > 0.0f)) return 0.05f;
  return 0.06f * leg / sides;
}

namespace {

// The axis (0 x, 1 y, 2 z) and sign nearest `v`, or axis -1 where v is within 37 degrees of none
// (or has no length).
struct NearestAxis {
  int axis = -1;
  float sign = 1.0f;
};
NearestAxis nearest_axis(const glm::vec3& v) {
  const float len = glm::length(v);
  if (!(len > 1e-6f) || !std::isfinite(len)) return {};
  int k = 0;
  for (int i = 1; i < 3; ++i) {
    if (std::abs(v[i]) > std::abs(v[k])) k = i;
  }
  if (std::abs(v[k]) < 0.8f * len) return {};
  return {k, v[k] < 0.0f ? -1.0f : 1.0f};
}

std::string axis_name(const NearestAxis& a) {
  return std::string(a.sign < 0.0f ? "-" : "+") + static_cast<char>('x' + a.axis);
}

// Feet to head in a model-space pose (zero where the roles are missing).
glm::vec3 body_up(const Skeleton& sk, const std::vector<glm::mat4>& model) {
  int top = -1;
  for (JointRole r : {JointRole::kHead, JointRole::kNeck, JointRole::kChest}) {
    if (top < 0) top = sk.role(r);
  }
  glm::vec3 feet(0.0f);
  int n = 0;
  for (Side s : {Side::kLeft, Side::kRight}) {
    const int f = sk.ankle(s) >= 0 ? sk.ankle(s) : sk.toe(s);
    if (f < 0) continue;
    feet += glm::vec3(model[f][3]);
    ++n;
  }
  if (top < 0 || n == 0) return glm::vec3(0.0f);
  return glm::vec3(model[top][3]) - feet / static_cast<float>(n);
}

}  // namespace

std::string stand_up_along_y(Skeleton* sk, Clip* clip) {
  std::vector<glm::mat4> model;
  local_to_model(*sk, sk->rest_rotations.data(), sk->rest_translations.data(), &model);
  const NearestAxis rest = nearest_axis(body_up(*sk, model));
  // The motion's up: feet to head, each frame's direction averaged over up to 64 frames.
  glm::vec3 sum(0.0f);
  const int step = std::max(1, clip->num_frames / 64);
  for (int f = 0; f < clip->num_frames; f += step) {
    local_to_model(*sk, clip->frame_rotations(f), clip->frame_translations(f), &model);
    const glm::vec3 v = body_up(*sk, model);
    const float len = glm::length(v);
    if (len > 1e-6f && std::isfinite(len)) sum += v / len;
  }
  const NearestAxis motion = nearest_axis(sum);
  if (rest.axis < 0 && motion.axis < 0) {
    return "+y (taken: no feet-to-head axis found in the rest pose or the motion)";
  }
  const bool motion_y = motion.axis == 1 && motion.sign > 0.0f;
  if (motion_y) return "+y (the motion stands along +y)";
  const NearestAxis up = rest.axis >= 0 ? rest : motion;
  if (up.axis == 1 && up.sign > 0.0f) return "+y (the rest pose stands along +y)";
  glm::vec3 from(0.0f);
  from[up.axis] = up.sign;
  const glm::vec3 to(0.0f, 1.0f, 0.0f);
  const glm::quat turn =
      up.axis == 1 ? glm::angleAxis(std::numbers::pi_v<float>, glm::vec3(1.0f, 0.0f, 0.0f))
                   : glm::rotation(from, to);
  for (int j = 0; j < sk->num_joints(); ++j) {
    if (sk->parents[j] >= 0) continue;
    sk->rest_translations[j] = turn * sk->rest_translations[j];
    sk->rest_rotations[j] = glm::normalize(turn * sk->rest_rotations[j]);
    for (int f = 0; f < clip->num_frames; ++f) {
      const size_t o = static_cast<size_t>(f) * clip->num_joints + j;
      clip->rotations[o] = glm::normalize(turn * clip->rotations[o]);
      clip->translations[o] = turn * clip->translations[o];
    }
  }
  return axis_name(up) + ": turned to stand along +y (the " +
         (rest.axis >= 0 ? "rest pose" : "motion") + " stands along " + axis_name(up) + ")";
}

std::string file_name(const std::string& path) {
  const size_t slash = path.find_last_of("/\\");
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

std::string file_stem(const std::string& path) {
  std::string name = file_name(path);
  const size_t dot = name.find_last_of('.');
  return dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
}

}  // namespace internal
}  // namespace gk
