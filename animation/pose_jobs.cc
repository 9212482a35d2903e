#include "animation/pose_jobs.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtx/quaternion.hpp>

namespace gk {
namespace {

// nlerp on the shortest arc: cheaper than slerp and, between neighbouring frames,
// indistinguishable.
glm::quat nlerp_shortest(const glm::quat& a, const glm::quat& b, float t) {
  const float sign = glm::dot(a, b) < 0.0f ? -1.0f : 1.0f;
  const glm::quat q = a * (1.0f - t) + (b * sign) * t;
  return glm::normalize(q);
}

float clamp_unit(float x) { return std::clamp(x, -1.0f, 1.0f); }

// Rotation taking unit vector `from` onto unit vector `to` (identity when either is degenerate).
glm::quat rotation_between(glm::vec3 from, glm::vec3 to) {
  const float lf = glm::length(from), lt = glm::length(to);
  if (lf < 1e-8f || lt < 1e-8f) return glm::quat(1, 0, 0, 0);
  from /= lf;
  to /= lt;
  const float d = clamp_unit(glm::dot(from, to));
  glm::vec3 axis = glm::cross(from, to);
  const float axis_len = glm::length(axis);
  if (axis_len < 1e-7f) {
    if (d > 0.0f) return glm::quat(1, 0, 0, 0);
    // Opposite vectors: any axis perpendicular to `from` will do.
    axis = glm::cross(from, std::abs(from.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0));
    return glm::angleAxis(glm::pi<float>(), glm::normalize(axis));
  }
  return glm::angleAxis(std::atan2(axis_len, d), axis / axis_len);
}

}  // namespace

float heading_of(const glm::vec3& dir) { return std::atan2(dir.x, dir.z); }

void clip_frame_model(const Clip& clip, const Skeleton& skeleton, int frame,
                      std::span<glm::mat4> out_model) {
  LocalToModelJob{&skeleton,
                  {clip.frame_rotations(frame), static_cast<size_t>(clip.num_joints)},
                  {clip.frame_translations(frame), static_cast<size_t>(clip.num_joints)},
                  glm::mat4(1.0f),
                  out_model}
      .run();
}

glm::vec3 horizontal_forward(const glm::mat4& m) {
  glm::vec3 f(m[2].x, 0.0f, m[2].z);
  const float len = glm::length(f);
  return len > 1e-6f ? f / len : glm::vec3(0.0f);
}

bool SampleClipJob::validate() const {
  if (!clip || clip->num_frames <= 0 || clip->fps <= 0.0f) return false;
  const size_t n = static_cast<size_t>(clip->num_joints);
  return out_rotations.size() >= n && out_translations.size() >= n &&
         clip->rotations.size() == n * clip->num_frames &&
         clip->translations.size() == n * clip->num_frames && std::isfinite(time_s);
}

void SampleClipJob::run() const {
  const int n = clip->num_joints;
  const int frames = clip->num_frames;
  float f = time_s * clip->fps;
  int i0, i1;
  float t;
  if (clip->loops) {
    f = std::fmod(f, static_cast<float>(frames));
    if (f < 0.0f) f += frames;
    i0 = std::min(static_cast<int>(f), frames - 1);
    i1 = (i0 + 1) % frames;
    t = f - i0;
  } else {
    f = std::clamp(f, 0.0f, static_cast<float>(frames - 1));
    i0 = std::min(static_cast<int>(f), frames - 1);
    i1 = std::min(i0 + 1, frames - 1);
    t = f - i0;
  }
  const glm::quat* r0 = clip->frame_rotations(i0);
  const glm::quat* r1 = clip->frame_rotations(i1);
  const glm::vec3* p0 = clip->frame_translations(i0);
  const glm::vec3* p1 = clip->frame_translations(i1);
  for (int j = 0; j < n; ++j) {
    out_rotations[j] = nlerp_shortest(r0[j], r1[j], t);
    out_translations[j] = glm::mix(p0[j], p1[j], t);
  }
  if (clip->loops && i1 < i0 && frames > 1) {
    // Across the wrap the root keeps travelling: frame 0 of the next loop lies one loop's
    // horizontal root displacement ahead (estimated from the clip's mean root velocity).
    const glm::vec3 first = clip->frame_translations(0)[0];
    const glm::vec3 last = clip->frame_translations(frames - 1)[0];
    glm::vec3 per_loop = (last - first) * (static_cast<float>(frames) / (frames - 1));
    per_loop.y = 0.0f;
    out_translations[0] += t * per_loop;
  }
}

bool BlendPosesJob::validate() const {
  if (layers.empty()) return false;
  const size_t n = out_rotations.size();
  if (out_translations.size() != n) return false;
  for (const PoseLayer& l : layers) {
    if (l.rotations.size() < n || l.translations.size() < n || !std::isfinite(l.weight)) {
      return false;
    }
  }
  return true;
}

void BlendPosesJob::run() const {
  float total = 0.0f;
  int first = -1, weighted = 0;
  for (size_t k = 0; k < layers.size(); ++k) {
    if (layers[k].weight > 0.0f) {
      total += layers[k].weight;
      if (first < 0) first = static_cast<int>(k);
      ++weighted;
    }
  }
  const size_t n = out_rotations.size();
  if (weighted <= 1) {  // one layer is the blend (unit rotations stay); none: the first unchanged
    const PoseLayer& only = layers[std::max(first, 0)];
    std::copy_n(only.rotations.begin(), n, out_rotations.begin());
    std::copy_n(only.translations.begin(), n, out_translations.begin());
    return;
  }
  const float inv_total = 1.0f / total;
  for (size_t j = 0; j < n; ++j) {
    const glm::quat ref = layers[first].rotations[j];
    glm::quat q(0, 0, 0, 0);
    glm::vec3 p(0.0f);
    for (const PoseLayer& l : layers) {
      if (l.weight <= 0.0f) continue;
      const float w = l.weight * inv_total;
      const glm::quat lq = l.rotations[j];
      q += (glm::dot(ref, lq) < 0.0f ? -w : w) * lq;
      p += w * l.translations[j];
    }
    out_rotations[j] = glm::normalize(q);
    out_translations[j] = p;
  }
}

bool LocalToModelJob::validate() const {
  if (!skeleton) return false;
  const int n = skeleton->num_joints();
  const size_t un = static_cast<size_t>(n);
  return rotations.size() >= un && translations.size() >= un && out_model.size() >= un &&
         from >= 0 && from <= n && (to < 0 || (to >= from && to <= n));
}

void LocalToModelJob::run() const {
  const int n = skeleton->num_joints();
  const int end = to < 0 ? n : std::min(to, n);
  for (int j = std::max(from, 0); j < end; ++j) {
    const int parent = skeleton->parents[j];
    const glm::mat4& p = parent < 0 ? root_transform : out_model[parent];
    // p * [R t; 0 1], leaving out the products with the local matrix's zeros (the sums keep glm's
    // order, so the result is glm's p * local to the bit).
    const glm::mat3 r = glm::mat3_cast(rotations[j]);
    const glm::vec3& t = translations[j];
    glm::mat4& m = out_model[j];
    m[0] = p[0] * r[0][0] + p[1] * r[0][1] + p[2] * r[0][2];
    m[1] = p[0] * r[1][0] + p[1] * r[1][1] + p[2] * r[1][2];
    m[2] = p[0] * r[2][0] + p[1] * r[2][1] + p[2] * r[2][2];
    m[3] = p[0] * t.x + p[1] * t.y + p[2] * t.z + p[3];
  }
}

bool TwoBoneIKJob::validate() const {
  return out_start_correction && out_mid_correction && std::isfinite(target.x) &&
         std::isfinite(target.y) && std::isfinite(target.z) && weight >= 0.0f && weight <= 1.0f;
}

void TwoBoneIKJob::run() const {
  // Three world-space rotations, composed R = R_twist * R_swing * R_bend about the start joint,
  // plus R_knee at the mid joint (see the derivation in docs: the law of cosines fixes the two
  // interior angles; the swing aims the chain at the target; the twist turns the knee to the pole).
  const glm::vec3 a = translation_of(start_model);
  const glm::vec3 b = translation_of(mid_model);
  const glm::vec3 c = translation_of(end_model);
  const float lab = glm::length(b - a);
  const float lcb = glm::length(c - b);
  *out_start_correction = glm::quat(1, 0, 0, 0);
  *out_mid_correction = glm::quat(1, 0, 0, 0);
  if (out_reached) *out_reached = false;
  if (lab < 1e-6f || lcb < 1e-6f || weight <= 0.0f) return;

  const float reach = glm::length(target - a);
  const float max_len = (lab + lcb) * max_extension;
  const float min_len = std::abs(lab - lcb) + 1e-4f;
  // Only reach beyond the pose's own is softened: a leg the animation itself stretches that far is
  // reached exactly (it straightens no faster than the animation does).
  float soft_reach = reach;
  const glm::vec3 ac = c - a;
  const float lac = glm::length(ac);
  const float soft_start =
      std::max(max_len * std::clamp(soften, 0.0f, 1.0f), std::min(lac, max_len));
  const float soft_span = max_len - soft_start;
  if (soft_span > 1e-6f && reach > soft_start) {
    soft_reach = soft_start + soft_span * (1.0f - std::exp(-(reach - soft_start) / soft_span));
  }
  const float lat = std::clamp(soft_reach, min_len, std::max(min_len, max_len));
  if (out_reached) *out_reached = reach <= max_len && reach >= min_len;

  // Current and desired interior angles.
  const glm::vec3 ab = glm::normalize(b - a), bc = glm::normalize(c - b);
  if (lac < 1e-6f) return;
  const glm::vec3 ac_n = ac / lac;
  const float ac_ab_0 = std::acos(clamp_unit(glm::dot(ac_n, ab)));
  const float ba_bc_0 = std::acos(clamp_unit(glm::dot(-ab, bc)));
  const float ac_ab_1 =
      std::acos(clamp_unit((lcb * lcb - lab * lab - lat * lat) / (-2.0f * lab * lat)));
  const float ba_bc_1 =
      std::acos(clamp_unit((lat * lat - lab * lab - lcb * lcb) / (-2.0f * lab * lcb)));

  // Bend plane normal: the current plane of the limb, or the pole plane when the limb is straight.
  glm::vec3 axis0 = glm::cross(ac_n, ab);
  if (glm::length(axis0) < 1e-5f) axis0 = glm::cross(ac_n, pole);
  if (glm::length(axis0) < 1e-5f) axis0 = glm::cross(ac_n, glm::vec3(1, 0, 0));
  axis0 = glm::normalize(axis0);

  const glm::quat r_bend = glm::angleAxis(ac_ab_1 - ac_ab_0, axis0);
  const glm::quat r_knee = glm::angleAxis(ba_bc_1 - ba_bc_0, axis0);
  // End joint after the bend, then swing the chain onto the target direction.
  const glm::vec3 c1 = a + r_bend * (b - a) + r_bend * (r_knee * (c - b));
  const glm::quat r_swing = rotation_between(c1 - a, target - a);
  glm::quat r = r_swing * r_bend;

  // Twist about the start-target axis so the knee points toward the pole.
  const glm::vec3 axis_t = glm::normalize(target - a);
  const glm::vec3 knee = r * (b - a);
  const glm::vec3 knee_p = knee - axis_t * glm::dot(knee, axis_t);
  const glm::vec3 pole_p = pole - axis_t * glm::dot(pole, axis_t);
  if (glm::length(knee_p) > 1e-5f && glm::length(pole_p) > 1e-5f) {
    const float twist =
        std::atan2(glm::dot(glm::cross(knee_p, pole_p), axis_t), glm::dot(knee_p, pole_p));
    r = glm::angleAxis(twist, axis_t) * r;
  }

  const glm::quat qa = glm::quat_cast(glm::mat3(start_model));
  const glm::quat qb = glm::quat_cast(glm::mat3(mid_model));
  glm::quat start_corr = glm::normalize(glm::inverse(qa) * r * qa);
  glm::quat mid_corr = glm::normalize(glm::inverse(qb) * r_knee * qb);
  if (weight < 1.0f) {
    const glm::quat id(1, 0, 0, 0);
    start_corr = nlerp_shortest(id, start_corr, weight);
    mid_corr = nlerp_shortest(id, mid_corr, weight);
  }
  *out_start_correction = start_corr;
  *out_mid_correction = mid_corr;
}

bool SkinningPaletteJob::validate() const {
  return model.size() == inverse_bind.size() && out_palette.size() >= model.size();
}

void SkinningPaletteJob::run() const {
  if (!affine_inverse_bind) {
    for (size_t j = 0; j < model.size(); ++j) out_palette[j] = model[j] * inverse_bind[j];
    return;
  }
  for (size_t j = 0; j < model.size(); ++j) {
    // As glm's product, leaving out the terms with the inverse bind's bottom-row zeros.
    const glm::mat4& a = model[j];
    const glm::mat4& b = inverse_bind[j];
    glm::mat4& m = out_palette[j];
    m[0] = a[0] * b[0][0] + a[1] * b[0][1] + a[2] * b[0][2];
    m[1] = a[0] * b[1][0] + a[1] * b[1][1] + a[2] * b[1][2];
    m[2] = a[0] * b[2][0] + a[1] * b[2][1] + a[2] * b[2][2];
    m[3] = a[0] * b[3][0] + a[1] * b[3][1] + a[2] * b[3][2] + a[3];
  }
}

bool is_affine(std::span<const glm::mat4> matrices) {
  for (const glm::mat4& m : matrices) {
    if (m[0][3] != 0.0f || m[1][3] != 0.0f || m[2][3] != 0.0f || m[3][3] != 1.0f) return false;
  }
  return true;
}

}  // namespace gk
