// The fast paths of the pose jobs against their plain reference implementations: TwoBoneIKJob
// (rotations built from cosines and sines, no acos, atan2, sin or cos) against the angle-based
// solver it replaced, and min_abs_dot (four joints at a time) against the scalar loop.

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "animation/pose_jobs.h"

namespace gk {
namespace {

// The angle-based two-bone IK as it was (law of cosines by acos, rotations by angleAxis, the
// swing by atan2 of the cross and dot products, the twist by atan2): the reference.
struct ReferenceIK {
  glm::quat start_correction{1, 0, 0, 0};
  glm::quat mid_correction{1, 0, 0, 0};
};

float clamp_unit(float x) { return std::clamp(x, -1.0f, 1.0f); }

glm::quat reference_rotation_between(glm::vec3 from, glm::vec3 to) {
  const float lf = glm::length(from), lt = glm::length(to);
  if (lf < 1e-8f || lt < 1e-8f) return glm::quat(1, 0, 0, 0);
  from /= lf;
  to /= lt;
  const float d = clamp_unit(glm::dot(from, to));
  glm::vec3 axis = glm::cross(from, to);
  const float axis_len = glm::length(axis);
  if (axis_len < 1e-7f) {
    if (d > 0.0f) return glm::quat(1, 0, 0, 0);
    axis = glm::cross(from, std::abs(from.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0));
    return glm::angleAxis(glm::pi<float>(), glm::normalize(axis));
  }
  return glm::angleAxis(std::atan2(axis_len, d), axis / axis_len);
}

ReferenceIK reference_two_bone_ik(const TwoBoneIKJob& job) {
  constexpr float kStraightLimb = 0.035f, kPi = 3.14159265358979f;
  ReferenceIK out;
  const glm::vec3 a = translation_of(job.start_model), b = translation_of(job.mid_model),
                  c = translation_of(job.end_model);
  const float lab = glm::length(b - a), lcb = glm::length(c - b);
  if (lab < 1e-6f || lcb < 1e-6f || job.weight <= 0.0f) return out;
  const float reach = glm::length(job.target - a);
  const float max_len = (lab + lcb) * job.max_extension;
  const float min_len = std::abs(lab - lcb) + 1e-4f;
  float soft_reach = reach;
  const glm::vec3 ac = c - a;
  const float lac = glm::length(ac);
  const float soft_start =
      std::max(max_len * std::clamp(job.soften, 0.0f, 1.0f), std::min(lac, max_len));
  const float soft_span = max_len - soft_start;
  if (soft_span > 1e-6f && reach > soft_start) {
    soft_reach = soft_start + soft_span * (1.0f - std::exp(-(reach - soft_start) / soft_span));
  }
  const float lat = std::clamp(soft_reach, min_len, std::max(min_len, max_len));
  const glm::vec3 ab = glm::normalize(b - a), bc = glm::normalize(c - b);
  if (lac < 1e-6f) return out;
  const glm::vec3 ac_n = ac / lac;
  const float ac_ab_0 = std::acos(clamp_unit(glm::dot(ac_n, ab)));
  const float ba_bc_0 = std::acos(clamp_unit(glm::dot(-ab, bc)));
  const float ac_ab_1 =
      std::acos(clamp_unit((lcb * lcb - lab * lab - lat * lat) / (-2.0f * lab * lat)));
  const float ba_bc_1 =
      std::acos(clamp_unit((lat * lat - lab * lab - lcb * lcb) / (-2.0f * lab * lcb)));
  glm::vec3 axis0 = glm::cross(ac_n, ab);
  float hip_0 = ac_ab_0, knee_0 = ba_bc_0;
  const float own = glm::length(axis0);
  const glm::vec3 pole_axis = glm::cross(ac_n, job.pole);
  if (own < kStraightLimb && glm::length(pole_axis) >= 1e-5f) {
    const glm::vec3 n = glm::normalize(pole_axis);
    const float along = own > 1e-9f ? glm::dot(axis0 / own, n) : 0.0f;
    hip_0 = along * ac_ab_0;
    knee_0 = kPi - along * (kPi - ba_bc_0);
    axis0 = n;
  }
  if (glm::length(axis0) < 1e-5f) axis0 = glm::cross(ac_n, glm::vec3(1, 0, 0));
  axis0 = glm::normalize(axis0);
  const glm::quat r_bend = glm::angleAxis(ac_ab_1 - hip_0, axis0);
  const glm::quat r_knee = glm::angleAxis(ba_bc_1 - knee_0, axis0);
  const glm::vec3 c1 = a + r_bend * (b - a) + r_bend * (r_knee * (c - b));
  glm::quat r = reference_rotation_between(c1 - a, job.target - a) * r_bend;
  const glm::vec3 axis_t = glm::normalize(job.target - a);
  const glm::vec3 knee = r * (b - a);
  const glm::vec3 knee_p = knee - axis_t * glm::dot(knee, axis_t);
  const glm::vec3 pole_p = job.pole - axis_t * glm::dot(job.pole, axis_t);
  if (glm::length(knee_p) > 1e-5f && glm::length(pole_p) > 1e-5f) {
    const float twist =
        std::atan2(glm::dot(glm::cross(knee_p, pole_p), axis_t), glm::dot(knee_p, pole_p));
    r = glm::angleAxis(twist, axis_t) * r;
  }
  const glm::quat qa = glm::quat_cast(glm::mat3(job.start_model));
  const glm::quat qb = glm::quat_cast(glm::mat3(job.mid_model));
  out.start_correction = glm::normalize(glm::inverse(qa) * r * qa);
  out.mid_correction = glm::normalize(glm::inverse(qb) * r_knee * qb);
  return out;
}

// Angle [rad] between two rotations (either sign of the quaternions), from the relative
// rotation's vector part: exact for small angles, where 2 acos(|dot|) resolves no better than
// about 7e-4 rad in floats.
float angle_between(const glm::quat& p, const glm::quat& q) {
  const glm::quat d = glm::inverse(glm::normalize(p)) * glm::normalize(q);
  return 2.0f * std::atan2(glm::length(glm::vec3(d.x, d.y, d.z)), std::abs(d.w));
}

// A hip-knee-ankle chain of the given bone lengths, the knee bent by `bend` [rad] about a random
// axis, the whole chain turned at random.
std::vector<glm::mat4> random_leg(std::mt19937& rng, float thigh, float shin, float bend) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const glm::quat hip_rot =
      glm::normalize(glm::quat(1.0f, 0.4f * u(rng), 0.4f * u(rng), 0.4f * u(rng)));
  const glm::vec3 bend_axis = glm::normalize(glm::vec3(1.0f, 0.2f * u(rng), 0.2f * u(rng)));
  std::vector<glm::mat4> m(3);
  m[0] = glm::mat4_cast(hip_rot);
  m[0][3] = glm::vec4(u(rng), 0.9f + 0.1f * u(rng), u(rng), 1.0f);
  glm::mat4 knee_local = glm::mat4_cast(glm::angleAxis(bend, bend_axis));
  knee_local[3] = glm::vec4(0.0f, -thigh, 0.0f, 1.0f);
  m[1] = m[0] * knee_local;
  glm::mat4 ankle_local(1.0f);
  ankle_local[3] = glm::vec4(0.0f, -shin, 0.0f, 1.0f);
  m[2] = m[1] * ankle_local;
  return m;
}

TEST(TwoBoneIKJobReference, SameCorrectionsAsTheAngleBasedSolver) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), u01(0.0f, 1.0f);
  float worst_start = 0.0f, worst_mid = 0.0f;
  int compared = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    // Bends from a hair off straight (inside and outside the 2 deg pole-plane band) to deep.
    const float bend = trial % 4 == 0 ? 0.1f * u01(rng) : 1.5f * u01(rng);
    const std::vector<glm::mat4> m =
        random_leg(rng, 0.4f + 0.1f * u01(rng), 0.4f + 0.1f * u01(rng), bend);
    const glm::vec3 hip = translation_of(m[0]);
    // Targets from close in to beyond full reach (soft and hard clamped).
    const glm::vec3 dir = glm::normalize(glm::vec3(0.6f * u(rng), -1.0f, 0.6f * u(rng)));
    const glm::vec3 target = hip + dir * (0.15f + 0.9f * u01(rng));
    TwoBoneIKJob job;
    job.start_model = m[0];
    job.mid_model = m[1];
    job.end_model = m[2];
    job.target = target;
    job.pole = glm::normalize(glm::vec3(u(rng), 0.3f * u(rng), 1.0f));
    job.soften = trial % 2 == 0 ? 0.98f : 1.0f;
    glm::quat c0, c1;
    job.out_start_correction = &c0;
    job.out_mid_correction = &c1;
    ASSERT_TRUE(job.validate());
    job.run();
    const ReferenceIK ref = reference_two_bone_ik(job);
    worst_start = std::max(worst_start, angle_between(c0, ref.start_correction));
    worst_mid = std::max(worst_mid, angle_between(c1, ref.mid_correction));
    ++compared;
  }
  // An angle from its cosine near 1 is ill-conditioned in either form (acos or half angles):
  // the two agree to float rounding amplified there (about 1e-5 rad; 5e-5 rad is 0.003 deg).
  EXPECT_LT(worst_start, 5e-5f) << "over " << compared << " chains";
  EXPECT_LT(worst_mid, 5e-5f) << "over " << compared << " chains";
}

// Half a turn of twist (the knee pointing away from the pole), where the half-angle form cancels
// and the solver falls back to the angle: still the reference's rotation.
TEST(TwoBoneIKJobReference, KneeOppositeThePoleTurnsHalfAround) {
  std::mt19937 rng(5);
  const std::vector<glm::mat4> m = random_leg(rng, 0.45f, 0.45f, 0.6f);
  const glm::vec3 a = translation_of(m[0]), b = translation_of(m[1]), c = translation_of(m[2]);
  const glm::vec3 axis = glm::normalize(c - a);
  glm::vec3 knee_side = (b - a) - axis * glm::dot(b - a, axis);
  TwoBoneIKJob job;
  job.start_model = m[0];
  job.mid_model = m[1];
  job.end_model = m[2];
  job.target = c;
  job.pole = -glm::normalize(knee_side);
  glm::quat c0, c1;
  job.out_start_correction = &c0;
  job.out_mid_correction = &c1;
  job.run();
  const ReferenceIK ref = reference_two_bone_ik(job);
  EXPECT_LT(angle_between(c0, ref.start_correction), 1e-3f);
  EXPECT_LT(angle_between(c1, ref.mid_correction), 1e-3f);
  // The knee really turned: the correction is about half a turn about the hip-target axis.
  EXPECT_GT(angle_between(c0, glm::quat(1, 0, 0, 0)), 3.0f);
}

// Both legs at once on SSE lanes: each leg's corrections the same bits as its job's own run(),
// over hips turned every way (every branch of quat_cast), bends from straight (the pole-plane
// band, run one by one) to deep, targets from close in to past full reach (the soft exp per lane)
// and poles across and opposite the knee (a twist near half a turn, one by one).
TEST(TwoBoneIKPair, SameBitsAsEachJobAlone) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), u01(0.0f, 1.0f);
  auto make = [&](int trial) {
    const float bend = trial % 5 == 0 ? 0.05f * u01(rng) : 1.5f * u01(rng);
    std::vector<glm::mat4> m = random_leg(rng, 0.4f + 0.1f * u01(rng), 0.4f + 0.1f * u01(rng), bend);
    // Any world orientation of the whole leg (random_leg turns its hip by at most ~45 deg).
    glm::mat4 turn = glm::mat4_cast(glm::normalize(glm::quat(u(rng), u(rng), u(rng), u(rng))));
    turn[3] = glm::vec4(u(rng), u(rng), u(rng), 1.0f);
    if (trial % 3 != 0) {
      for (glm::mat4& j : m) j = turn * j;
    }
    const glm::vec3 hip = translation_of(m[0]), ankle = translation_of(m[2]);
    const glm::vec3 dir = glm::normalize(ankle - hip + 0.5f * glm::vec3(u(rng), u(rng), u(rng)));
    TwoBoneIKJob job;
    job.start_model = m[0];
    job.mid_model = m[1];
    job.end_model = m[2];
    job.target = hip + dir * (0.05f + 1.0f * u01(rng));
    job.pole = trial % 7 == 0 ? -(translation_of(m[1]) - hip)
                              : glm::normalize(glm::vec3(u(rng), 0.3f * u(rng), 1.0f));
    job.soften = trial % 2 == 0 ? 0.98f : 1.0f;
    job.max_extension = trial % 4 == 0 ? 1.0f : 0.999f;
    return job;
  };
  auto same = [](const glm::quat& p, const glm::quat& q) {
    return std::memcmp(&p, &q, sizeof(glm::quat)) == 0;
  };
  int differing = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    TwoBoneIKJob ja = make(trial), jb = make(trial / 2);
    glm::quat a0, a1, b0, b1, ra0, ra1, rb0, rb1;
    ja.out_start_correction = &ra0;
    ja.out_mid_correction = &ra1;
    jb.out_start_correction = &rb0;
    jb.out_mid_correction = &rb1;
    ja.run();
    jb.run();
    ja.out_start_correction = &a0;
    ja.out_mid_correction = &a1;
    jb.out_start_correction = &b0;
    jb.out_mid_correction = &b1;
    two_bone_ik_pair(ja, jb);
    if (!same(a0, ra0) || !same(a1, ra1) || !same(b0, rb0) || !same(b1, rb1)) ++differing;
  }
  EXPECT_EQ(differing, 0);
}

TEST(MinAbsDot, SameAsTheScalarLoop) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (size_t n : {0u, 1u, 3u, 4u, 5u, 24u, 25u, 52u, 53u}) {
    std::vector<glm::quat> a(n), b(n);
    for (size_t j = 0; j < n; ++j) {
      a[j] = glm::normalize(glm::quat(u(rng), u(rng), u(rng), u(rng)));
      b[j] = glm::normalize(a[j] + 0.3f * glm::quat(u(rng), u(rng), u(rng), u(rng)));
      if (j % 3 == 1) b[j] = -b[j];  // either sign of a rotation
    }
    if (n > 6) b[5] = glm::quat(std::numeric_limits<float>::quiet_NaN(), 0, 0, 0);  // skipped
    float expected = 1.0f;
    for (size_t j = 0; j < n; ++j) expected = std::min(expected, std::abs(glm::dot(a[j], b[j])));
    EXPECT_EQ(min_abs_dot(a, b), expected) << n << " joints";
    // The fused form: the same minimum, and b is a afterwards (every joint, the remainder too).
    std::vector<glm::quat> kept = b;
    EXPECT_EQ(min_abs_dot_then_copy(a, kept), expected) << n << " joints";
    for (size_t j = 0; j < n; ++j) EXPECT_EQ(kept[j], a[j]) << n << " joints, joint " << j;
  }
}

}  // namespace
}  // namespace gk
