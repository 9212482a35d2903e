#include "animation/pose_jobs.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#include <xmmintrin.h>
#endif

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtx/quaternion.hpp>

#include "animation/fk_compose.h"
#include "animation/near_fmod.h"
#include "animation/quat_sse.h"

namespace gk {
namespace {

// [sin of the angle] a limb closer to straight than this (2 deg) bends in the pole's plane.
constexpr float kStraightLimb = 0.035f;
constexpr float kPi = 3.14159265358979f;

// nlerp on the shortest arc: cheaper than slerp and, between neighbouring frames,
// indistinguishable.
glm::quat nlerp_shortest(const glm::quat& a, const glm::quat& b, float t) {
  const float sign = glm::dot(a, b) < 0.0f ? -1.0f : 1.0f;
  const glm::quat q = a * (1.0f - t) + (b * sign) * t;
  return glm::normalize(q);
}

float clamp_unit(float x) { return std::clamp(x, -1.0f, 1.0f); }

#if defined(__SSE2__)
// Four joints at once, one per SIMD lane (quaternions transposed to x, y, z, w rows). Every lane
// does the scalar code's operations in its order (glm's dot pairs (w, x) and (y, z); sqrt and
// division are correctly rounded either way), so the results are the same bits.
struct Quat4 {
  __m128 x, y, z, w;
};

Quat4 load4(const glm::quat* q) {
  Quat4 r{_mm_loadu_ps(&q[0].x), _mm_loadu_ps(&q[1].x), _mm_loadu_ps(&q[2].x),
          _mm_loadu_ps(&q[3].x)};
  _MM_TRANSPOSE4_PS(r.x, r.y, r.z, r.w);
  return r;
}

void store4(Quat4 r, glm::quat* q) {
  _MM_TRANSPOSE4_PS(r.x, r.y, r.z, r.w);
  _mm_storeu_ps(&q[0].x, r.x);
  _mm_storeu_ps(&q[1].x, r.y);
  _mm_storeu_ps(&q[2].x, r.z);
  _mm_storeu_ps(&q[3].x, r.w);
}

__m128 dot4(const Quat4& a, const Quat4& b) {
  return _mm_add_ps(_mm_add_ps(_mm_mul_ps(a.w, b.w), _mm_mul_ps(a.x, b.x)),
                    _mm_add_ps(_mm_mul_ps(a.y, b.y), _mm_mul_ps(a.z, b.z)));
}

// a * wa + b * wb, b negated in the lanes where `negate` is set (sign flip, exact).
Quat4 weighted_sum4(const Quat4& a, __m128 wa, const Quat4& b, __m128 wb, __m128 negate) {
  const __m128 sign = _mm_and_ps(negate, _mm_set1_ps(-0.0f));
  auto lane = [&](__m128 pa, __m128 pb) {
    return _mm_add_ps(_mm_mul_ps(pa, wa), _mm_mul_ps(_mm_xor_ps(pb, sign), wb));
  };
  return {lane(a.x, b.x), lane(a.y, b.y), lane(a.z, b.z), lane(a.w, b.w)};
}

// Lane k of v in all four lanes (the bits moved, not computed).
template <int k>
__m128 broadcast_lane(__m128 v) {
  return _mm_castsi128_ps(_mm_shuffle_epi32(_mm_castps_si128(v), _MM_SHUFFLE(k, k, k, k)));
}

// glm::normalize: q / |q|, identity where |q| <= 0.
Quat4 normalize4(const Quat4& q) {
  const __m128 len = _mm_sqrt_ps(dot4(q, q));
  const __m128 inv = _mm_div_ps(_mm_set1_ps(1.0f), len);
  const __m128 bad = _mm_cmple_ps(len, _mm_setzero_ps());
  auto keep = [&](__m128 v) { return _mm_andnot_ps(bad, _mm_mul_ps(v, inv)); };
  return {keep(q.x), keep(q.y), keep(q.z),
          _mm_or_ps(keep(q.w), _mm_and_ps(bad, _mm_set1_ps(1.0f)))};
}
#endif

// out[i] = a[i] * wa + b[i] * wb over n floats (glm::mix with wa = 1 - t, wb = t, element by
// element; also a two-layer weighted mean).
void weighted_floats(const float* a, float wa, const float* b, float wb, size_t n, float* out) {
  size_t i = 0;
#if defined(__SSE2__)
  const __m128 wa4 = _mm_set1_ps(wa), wb4 = _mm_set1_ps(wb);
  for (; i + 4 <= n; i += 4) {
    _mm_storeu_ps(out + i, _mm_add_ps(_mm_mul_ps(_mm_loadu_ps(a + i), wa4),
                                      _mm_mul_ps(_mm_loadu_ps(b + i), wb4)));
  }
#endif
  for (; i < n; ++i) out[i] = a[i] * wa + b[i] * wb;
}

// Rotation by the angle whose cosine and sine are proportional to (c, s) (atan2(s, c), any common
// positive scale) about the unit axis, without the angle: the half-angle quaternion is
// proportional to (1 + cos, sin axis) = (r + c, s axis) / r. Exact in value; near half a turn
// (r + c small against r) that cancels, so the angle is taken there.
glm::quat rotation_of_cos_sin(float c, float s, const glm::vec3& axis) {
  const float r = std::sqrt(c * c + s * s);
  if (!(r > 0.0f)) return glm::quat(1, 0, 0, 0);
  if (r + c < 1e-3f * r) return glm::angleAxis(std::atan2(s, c), axis);
  return glm::normalize(glm::quat(r + c, s * axis.x, s * axis.y, s * axis.z));
}

// cos and sin of half of acos(c) for c in [-1, 1] (both >= 0: the angle is in [0, pi]).
struct HalfAngle {
  float cos, sin;
};
HalfAngle half_of_acos(float c) {
  return {std::sqrt(std::max(0.0f, 0.5f * (1.0f + c))),
          std::sqrt(std::max(0.0f, 0.5f * (1.0f - c)))};
}

// Rotation by acos(c1) - acos(c0) about the unit axis: the half angles' difference by the
// angle-difference identities (no acos, no sin or cos).
glm::quat rotation_by_acos_difference(float c1, float c0, const glm::vec3& axis) {
  const HalfAngle h1 = half_of_acos(c1), h0 = half_of_acos(c0);
  const float cw = h1.cos * h0.cos + h1.sin * h0.sin;
  const float sw = h1.sin * h0.cos - h1.cos * h0.sin;
  return glm::quat(cw, sw * axis.x, sw * axis.y, sw * axis.z);
}

// Rotation taking vector `from` onto vector `to` (identity when either is degenerate), without
// the angle: the half-way quaternion (1 + cos, from x to), normalised (rotation_of_cos_sin, which
// takes the angle only near half a turn).
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
  return rotation_of_cos_sin(d, axis_len, axis / axis_len);
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

namespace {

// Joints in [0, n), ascending.
bool valid_joint_list(std::span<const int16_t> joints, size_t n) {
  for (size_t i = 0; i < joints.size(); ++i) {
    if (joints[i] < 0 || static_cast<size_t>(joints[i]) >= n) return false;
    if (i > 0 && joints[i] <= joints[i - 1]) return false;
  }
  return true;
}

}  // namespace

bool valid_runs(std::span<const JointRun> runs, size_t n) {
  int last = 0;
  for (const JointRun& r : runs) {
    if (r.from < last || r.to <= r.from || static_cast<size_t>(r.to) > n) return false;
    last = r.to;
  }
  return true;
}

bool SampleClipJob::validate() const {
  if (!clip || clip->num_frames <= 0 || clip->fps <= 0.0f) return false;
  const size_t n = static_cast<size_t>(clip->num_joints);
  return out_rotations.size() >= n && out_translations.size() >= n &&
         valid_joint_list(translated_joints, n) && valid_runs(sampled_runs, n) &&
         clip->rotations.size() == n * clip->num_frames &&
         clip->translations.size() == n * clip->num_frames && std::isfinite(time_s);
}

namespace {

// The two frames a clip is sampled between at time_s, and the weight of the second.
struct FramePair {
  int i0, i1;
  float t;
};

FramePair frame_pair(const Clip& clip, float time_s) {
  const int frames = clip.num_frames;
  float f = time_s * clip.fps;
  FramePair fp;
  if (clip.loops) {
    // fmod returns an f already in [0, frames) as it is: skip the call (same bits).
    if (!(f >= 0.0f && f < static_cast<float>(frames))) {
      f = near_fmod(f, static_cast<float>(frames));
      if (f < 0.0f) f += frames;
    }
    fp.i0 = std::min(static_cast<int>(f), frames - 1);
    fp.i1 = (fp.i0 + 1) % frames;
  } else {
    f = std::clamp(f, 0.0f, static_cast<float>(frames - 1));
    fp.i0 = std::min(static_cast<int>(f), frames - 1);
    fp.i1 = std::min(fp.i0 + 1, frames - 1);
  }
  fp.t = f - fp.i0;
  return fp;
}

// The two frames are somewhere in the clip, likely out of the caches: ask for all their lines at
// once rather than one stream after the other.
// With a list of translated joints, only their translations' lines (from the first to the last).
void prefetch_frames(const Clip& clip, const FramePair& fp, std::span<const int16_t> translated) {
  const size_t n = static_cast<size_t>(clip.num_joints);
  prefetch_bytes(clip.frame_rotations(fp.i0), n * sizeof(glm::quat));
  prefetch_bytes(clip.frame_rotations(fp.i1), n * sizeof(glm::quat));
  const size_t first = translated.empty() ? 0 : static_cast<size_t>(translated.front());
  const size_t count = translated.empty() ? n : translated.back() + 1 - first;
  prefetch_bytes(clip.frame_translations(fp.i0) + first, count * sizeof(glm::vec3));
  prefetch_bytes(clip.frame_translations(fp.i1) + first, count * sizeof(glm::vec3));
}

// a * wa + b * wb, component by component (weighted_floats' arithmetic for one joint).
glm::vec3 weighted_vec3(const glm::vec3& a, float wa, const glm::vec3& b, float wb) {
  return {a.x * wa + b.x * wb, a.y * wa + b.y * wb, a.z * wa + b.z * wb};
}

// Across a loop's wrap the root keeps travelling: frame 0 of the next loop lies one loop's
// horizontal root displacement ahead (estimated from the clip's mean root velocity). What to add
// to the sampled root translation (0 away from the wrap).
bool crosses_wrap(const Clip& clip, const FramePair& fp) {
  return clip.loops && fp.i1 < fp.i0 && clip.num_frames > 1;
}
glm::vec3 wrap_step(const Clip& clip, const FramePair& fp) {
  const int frames = clip.num_frames;
  const glm::vec3 first = clip.frame_translations(0)[0];
  const glm::vec3 last = clip.frame_translations(frames - 1)[0];
  glm::vec3 per_loop = (last - first) * (static_cast<float>(frames) / (frames - 1));
  per_loop.y = 0.0f;
  return fp.t * per_loop;
}

#if defined(__SSE2__)
// One clip's rotations of joints [j, j + 4) at its frame pair (SampleClipJob's arithmetic).
// Inlined: a call would pass the four registers of the result through memory.
[[gnu::always_inline]] inline Quat4 sample4(const glm::quat* r0, const glm::quat* r1, __m128 s4,
                                            __m128 t4) {
  const Quat4 a = load4(r0), b = load4(r1);
  const __m128 negate = _mm_cmplt_ps(dot4(a, b), _mm_setzero_ps());
  return normalize4(weighted_sum4(a, s4, b, t4, negate));
}

// The last count (< 4) rotations from q, padded with identities to four: the joints a SIMD loop
// leaves go through it too (a lane computes what the scalar code would; the padding is dropped).
struct Tail4 {
  glm::quat q[4];
  Tail4(const glm::quat* from, int count) {
    for (int k = 0; k < 4; ++k) q[k] = k < count ? from[k] : glm::quat(1, 0, 0, 0);
  }
};
#endif

}  // namespace

void SampleClipJob::run() const {
  const int n = clip->num_joints;
  const FramePair fp = frame_pair(*clip, time_s);
  const float t = fp.t;
  const glm::quat* r0 = clip->frame_rotations(fp.i0);
  const glm::quat* r1 = clip->frame_rotations(fp.i1);
  const glm::vec3* p0 = clip->frame_translations(fp.i0);
  const glm::vec3* p1 = clip->frame_translations(fp.i1);
  prefetch_frames(*clip, fp, translated_joints);
#if defined(__SSE2__)
  const __m128 s4 = _mm_set1_ps(1.0f - t), t4 = _mm_set1_ps(t);
#endif
  auto rotations = [&](const int from, const int to) __attribute__((always_inline)) {
    int j = from;
#if defined(__SSE2__)
    for (; j + 4 <= to; j += 4) store4(sample4(r0 + j, r1 + j, s4, t4), out_rotations.data() + j);
    if (j < to && to - from >= 4) {
      // The last four joints again (each lane's arithmetic is its own: the ones done already
      // come out the same), rather than the rest padded through a copy.
      store4(sample4(r0 + to - 4, r1 + to - 4, s4, t4), out_rotations.data() + to - 4);
      j = to;
    }
    if (j < to) {
      const Tail4 a(r0 + j, to - j), b(r1 + j, to - j);
      glm::quat out[4];
      store4(sample4(a.q, b.q, s4, t4), out);
      std::copy_n(out, to - j, out_rotations.data() + j);
      j = to;
    }
#endif
    for (; j < to; ++j) out_rotations[j] = nlerp_shortest(r0[j], r1[j], t);
  };
  const JointRun every{0, n};
  const std::span<const JointRun> runs =
      sampled_runs.empty() ? std::span<const JointRun>(&every, 1) : sampled_runs;
  for (const JointRun& r : runs) rotations(r.from, r.to);
  if (!translated_joints.empty()) {  // the listed joints only, with weighted_floats' arithmetic
    for (const int16_t k : translated_joints) {
      out_translations[k] = weighted_vec3(p0[k], 1.0f - t, p1[k], t);
    }
    if (translated_joints.front() == 0 && crosses_wrap(*clip, fp)) {
      out_translations[0] += wrap_step(*clip, fp);
    }
    return;
  }
  auto translations = [&](const int from, const int to) __attribute__((always_inline)) {
    weighted_floats(reinterpret_cast<const float*>(p0 + from), 1.0f - t,
                    reinterpret_cast<const float*>(p1 + from), t, 3 * static_cast<size_t>(to - from),
                    reinterpret_cast<float*>(out_translations.data() + from));
  };
  for (const JointRun& r : runs) translations(r.from, r.to);
  if (runs.front().from == 0 && crosses_wrap(*clip, fp)) {
    out_translations[0] += wrap_step(*clip, fp);
  }
}

bool SampleBlendJob::validate() const {
  if (!a.clip || !b.clip || a.clip->num_joints != b.clip->num_joints) return false;
  if (!(a.weight > 0.0f) || !(b.weight > 0.0f) || !std::isfinite(a.weight + b.weight)) {
    return false;
  }
  for (const Input* in : {&a, &b}) {
    if (!SampleClipJob{in->clip, in->time_s, out_rotations, out_translations, translated_joints,
                       sampled_runs}
             .validate()) {
      return false;
    }
  }
  return true;
}

void SampleBlendJob::run() const {
  const int n = a.clip->num_joints;
  const FramePair fa = frame_pair(*a.clip, a.time_s), fb = frame_pair(*b.clip, b.time_s);
  prefetch_frames(*a.clip, fa, translated_joints);
  prefetch_frames(*b.clip, fb, translated_joints);
  // BlendPosesJob's weights: each over their sum.
  const float inv_total = 1.0f / (a.weight + b.weight);
  const float wa = a.weight * inv_total, wb = b.weight * inv_total;
  const glm::quat* a0r = a.clip->frame_rotations(fa.i0);
  const glm::quat* a1r = a.clip->frame_rotations(fa.i1);
  const glm::quat* b0r = b.clip->frame_rotations(fb.i0);
  const glm::quat* b1r = b.clip->frame_rotations(fb.i1);
#if defined(__SSE2__)
  const __m128 sa = _mm_set1_ps(1.0f - fa.t), ta = _mm_set1_ps(fa.t);
  const __m128 sb = _mm_set1_ps(1.0f - fb.t), tb = _mm_set1_ps(fb.t);
  const __m128 wa4 = _mm_set1_ps(wa), wb4 = _mm_set1_ps(wb);
  // Inlined (a call would pass the sampled rotations through memory).
  auto blend4 = [&](const glm::quat* ra0, const glm::quat* ra1, const glm::quat* rb0,
                    const glm::quat* rb1, glm::quat* out) __attribute__((always_inline)) {
    const Quat4 qa = sample4(ra0, ra1, sa, ta), qb = sample4(rb0, rb1, sb, tb);
    const __m128 negate = _mm_cmplt_ps(dot4(qa, qb), _mm_setzero_ps());
    store4(normalize4(weighted_sum4(qa, wa4, qb, wb4, negate)), out);
  };
#endif
  auto rotations = [&](const int from, const int to) __attribute__((always_inline)) {
    int j = from;
#if defined(__SSE2__)
    for (; j + 4 <= to; j += 4) {
      blend4(a0r + j, a1r + j, b0r + j, b1r + j, out_rotations.data() + j);
    }
    if (j < to && to - from >= 4) {  // the last four again, as SampleClipJob's
      const int k = to - 4;
      blend4(a0r + k, a1r + k, b0r + k, b1r + k, out_rotations.data() + k);
      j = to;
    }
    if (j < to) {  // the rest padded to four (as the loop below, but for the sign of a zero)
      const Tail4 ta0(a0r + j, to - j), ta1(a1r + j, to - j), tb0(b0r + j, to - j),
          tb1(b1r + j, to - j);
      glm::quat out[4];
      blend4(ta0.q, ta1.q, tb0.q, tb1.q, out);
      std::copy_n(out, to - j, out_rotations.data() + j);
      j = to;
    }
#endif
    for (; j < to; ++j) {  // BlendPosesJob's loop over the joints its SIMD loop leaves
      const glm::quat qa = nlerp_shortest(a0r[j], a1r[j], fa.t);
      const glm::quat qb = nlerp_shortest(b0r[j], b1r[j], fb.t);
      glm::quat q(0, 0, 0, 0);
      q += wa * qa;
      q += (glm::dot(qa, qb) < 0.0f ? -wb : wb) * qb;
      out_rotations[j] = glm::normalize(q);
    }
  };
  const JointRun every{0, n};
  const std::span<const JointRun> runs =
      sampled_runs.empty() ? std::span<const JointRun>(&every, 1) : sampled_runs;
  for (const JointRun& r : runs) rotations(r.from, r.to);
  // Translations: each clip's lerp (its root moved on across a wrap), then the weighted mean.
  const float* a0 = reinterpret_cast<const float*>(a.clip->frame_translations(fa.i0));
  const float* a1 = reinterpret_cast<const float*>(a.clip->frame_translations(fa.i1));
  const float* b0 = reinterpret_cast<const float*>(b.clip->frame_translations(fb.i0));
  const float* b1 = reinterpret_cast<const float*>(b.clip->frame_translations(fb.i1));
  float* out = reinterpret_cast<float*>(out_translations.data());
  if (!translated_joints.empty()) {  // the listed joints only, with the loops' arithmetic below
    for (const int16_t k : translated_joints) {
      if (k == 0) continue;  // the root below, with the wraps
      const float* pa0 = a0 + 3 * k;
      const float* pa1 = a1 + 3 * k;
      const float* pb0 = b0 + 3 * k;
      const float* pb1 = b1 + 3 * k;
      for (int c = 0; c < 3; ++c) {
        const float la = pa0[c] * (1.0f - fa.t) + pa1[c] * fa.t;
        const float lb = pb0[c] * (1.0f - fb.t) + pb1[c] * fb.t;
        out[3 * k + c] = la * wa + lb * wb;
      }
    }
  }
  const bool listed = !translated_joints.empty();
  const bool root_sampled = runs.front().from == 0;
  if (root_sampled && (!listed || translated_joints.front() == 0)) {  // with the wraps
    glm::vec3 ra(a0[0] * (1.0f - fa.t) + a1[0] * fa.t, a0[1] * (1.0f - fa.t) + a1[1] * fa.t,
                 a0[2] * (1.0f - fa.t) + a1[2] * fa.t);
    glm::vec3 rb(b0[0] * (1.0f - fb.t) + b1[0] * fb.t, b0[1] * (1.0f - fb.t) + b1[1] * fb.t,
                 b0[2] * (1.0f - fb.t) + b1[2] * fb.t);
    if (crosses_wrap(*a.clip, fa)) ra += wrap_step(*a.clip, fa);
    if (crosses_wrap(*b.clip, fb)) rb += wrap_step(*b.clip, fb);
    out_translations[0] = glm::vec3(ra.x * wa + rb.x * wb, ra.y * wa + rb.y * wb,
                                    ra.z * wa + rb.z * wb);
  }
  if (listed) return;  // the listed joints are done
#if defined(__SSE2__)
  const __m128 sa1 = _mm_set1_ps(1.0f - fa.t), ta1 = _mm_set1_ps(fa.t);
  const __m128 sb1 = _mm_set1_ps(1.0f - fb.t), tb1 = _mm_set1_ps(fb.t);
  const __m128 wa1 = _mm_set1_ps(wa), wb1 = _mm_set1_ps(wb);
#endif
  // Floats [from, end) (the root's, 0-2, done above).
  auto translations = [&](size_t i, const size_t end) __attribute__((always_inline)) {
#if defined(__SSE2__)
    for (; i + 4 <= end; i += 4) {
      const __m128 la = _mm_add_ps(_mm_mul_ps(_mm_loadu_ps(a0 + i), sa1),
                                   _mm_mul_ps(_mm_loadu_ps(a1 + i), ta1));
      const __m128 lb = _mm_add_ps(_mm_mul_ps(_mm_loadu_ps(b0 + i), sb1),
                                   _mm_mul_ps(_mm_loadu_ps(b1 + i), tb1));
      _mm_storeu_ps(out + i, _mm_add_ps(_mm_mul_ps(la, wa1), _mm_mul_ps(lb, wb1)));
    }
#endif
    for (; i < end; ++i) {
      const float la = a0[i] * (1.0f - fa.t) + a1[i] * fa.t;
      const float lb = b0[i] * (1.0f - fb.t) + b1[i] * fb.t;
      out[i] = la * wa + lb * wb;
    }
  };
  for (const JointRun& r : runs) {
    translations(std::max<size_t>(3, 3 * static_cast<size_t>(r.from)),
                 3 * static_cast<size_t>(r.to));
  }
}

bool BlendPosesJob::validate() const {
  if (layers.empty()) return false;
  const size_t n = out_rotations.size();
  if (out_translations.size() != n || !valid_joint_list(translated_joints, n)) return false;
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
  const bool listed = !translated_joints.empty();
  if (weighted <= 1) {  // one layer is the blend (unit rotations stay); none: the first unchanged
    const PoseLayer& only = layers[std::max(first, 0)];
    std::copy_n(only.rotations.begin(), n, out_rotations.begin());
    if (!listed) {
      std::copy_n(only.translations.begin(), n, out_translations.begin());
    } else {
      for (const int16_t k : translated_joints) out_translations[k] = only.translations[k];
    }
    return;
  }
  const float inv_total = 1.0f / total;
  if (listed) {  // the listed joints' translations as the scalar loop below has them
    for (const int16_t k : translated_joints) {
      glm::vec3 p(0.0f);
      for (const PoseLayer& l : layers) {
        if (l.weight > 0.0f) p += (l.weight * inv_total) * l.translations[k];
      }
      out_translations[k] = p;
    }
  }
  size_t j = 0;
#if defined(__SSE2__)
  if (weighted == 2) {
    // Two layers (the usual blend), four joints at a time: the loop below's operations in its
    // order (0 + w a is w a, but for the sign of a zero), so the same numbers.
    int second = first + 1;
    while (layers[second].weight <= 0.0f) ++second;
    const PoseLayer& la = layers[first];
    const PoseLayer& lb = layers[second];
    const float wa = la.weight * inv_total, wb = lb.weight * inv_total;
    const __m128 wa4 = _mm_set1_ps(wa), wb4 = _mm_set1_ps(wb);
    for (; j + 4 <= n; j += 4) {
      const Quat4 a = load4(la.rotations.data() + j), b = load4(lb.rotations.data() + j);
      // The first layer is its own reference: dot(a, a) >= 0 keeps its weight positive.
      const __m128 negate = _mm_cmplt_ps(dot4(a, b), _mm_setzero_ps());
      store4(normalize4(weighted_sum4(a, wa4, b, wb4, negate)), out_rotations.data() + j);
    }
    if (!listed) {
      weighted_floats(reinterpret_cast<const float*>(la.translations.data()), wa,
                      reinterpret_cast<const float*>(lb.translations.data()), wb, 3 * n,
                      reinterpret_cast<float*>(out_translations.data()));
    }
  } else {
    // Three or more layers (a blend with a take's seam), four joints at a time: the loop below's
    // sums from 0 in its order, each lane one joint, so the same bits (the scalar loop cost four
    // times as much).
    const __m128 zero = _mm_setzero_ps(), sign_bit = _mm_set1_ps(-0.0f);
    for (; j + 4 <= n; j += 4) {
      const Quat4 ref = load4(layers[first].rotations.data() + j);
      Quat4 q{zero, zero, zero, zero};
      for (const PoseLayer& l : layers) {
        if (l.weight <= 0.0f) continue;
        const Quat4 lq = load4(l.rotations.data() + j);
        // -w where the layer is in the other hemisphere than the first one: a sign flip, exact.
        const __m128 w = _mm_xor_ps(_mm_set1_ps(l.weight * inv_total),
                                    _mm_and_ps(_mm_cmplt_ps(dot4(ref, lq), zero), sign_bit));
        q.x = _mm_add_ps(q.x, _mm_mul_ps(w, lq.x));
        q.y = _mm_add_ps(q.y, _mm_mul_ps(w, lq.y));
        q.z = _mm_add_ps(q.z, _mm_mul_ps(w, lq.z));
        q.w = _mm_add_ps(q.w, _mm_mul_ps(w, lq.w));
      }
      store4(normalize4(q), out_rotations.data() + j);
    }
    if (!listed) {  // every joint's translation, as floats (the joints after j again below)
      float* out = reinterpret_cast<float*>(out_translations.data());
      const size_t m = 3 * n;
      size_t i = 0;
      for (; i + 4 <= m; i += 4) {
        __m128 p = zero;
        for (const PoseLayer& l : layers) {
          if (l.weight <= 0.0f) continue;
          const float* t = reinterpret_cast<const float*>(l.translations.data());
          p = _mm_add_ps(p, _mm_mul_ps(_mm_set1_ps(l.weight * inv_total), _mm_loadu_ps(t + i)));
        }
        _mm_storeu_ps(out + i, p);
      }
      for (; i < m; ++i) {
        float p = 0.0f;
        for (const PoseLayer& l : layers) {
          if (l.weight <= 0.0f) continue;
          p += (l.weight * inv_total) * reinterpret_cast<const float*>(l.translations.data())[i];
        }
        out[i] = p;
      }
    }
  }
#endif
  for (; j < n; ++j) {
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
    if (!listed) out_translations[j] = p;
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
  int j = std::max(from, 0);
#if defined(__SSE2__)
  // p * [R t; 0 1] as glm's p * local, leaving out the products with the local matrix's zeros
  // (the sums in glm's order: the same bits). The rotation matrices of four joints at once (they
  // do not depend on the parents), each lane glm::mat3_cast's operations in its order; each joint
  // then takes its lane's entries, broadcast, straight from the registers.
  // The arrays through locals: the stores below are through may-alias vector pointers, after
  // which members read through `this` would be loaded again for every joint.
  const int16_t* parents = skeleton->parents.data();
  const float* root = &root_transform[0].x;
  float* model = &(*out_model.data())[0].x;
  // A joint's local translation (x, y, z) in k0, k1, k2 of the three registers t holding four
  // joints' twelve floats: broadcast from there (one pshufd each, no scalar load and shuffle).
  auto compose = [&](int joint, const __m128* e, const __m128* t, auto lane) {
    constexpr int k = decltype(lane)::value;
    // pshufd broadcasts a lane in one instruction (shufps needs a register copy first).
    auto at = [&](int i) { return broadcast_lane<k>(e[i]); };
    auto tr = [&](auto c) {
      constexpr int f = 3 * k + decltype(c)::value;
      return broadcast_lane<f % 4>(t[f / 4]);
    };
    const int parent = parents[joint];
    const __m128 r[9] = {at(0), at(1), at(2), at(3), at(4), at(5), at(6), at(7), at(8)};
    fk::compose(parent < 0 ? root : model + 16 * parent, r, tr(std::integral_constant<int, 0>{}),
                tr(std::integral_constant<int, 1>{}), tr(std::integral_constant<int, 2>{}),
                model + 16 * joint);
  };
  // The rotation matrices of the four joints from q4 on (their translations from t4, twelve
  // floats); the first `count` of them composed.
  auto group = [&](int first, const glm::quat* q4, const float* t4, int count)
      __attribute__((always_inline)) {
    const Quat4 q = load4(q4);
    __m128 e[9];
    quat_sse::rotation_entries4(q.x, q.y, q.z, q.w, e);
    const __m128 t[3] = {_mm_loadu_ps(t4), _mm_loadu_ps(t4 + 4), _mm_loadu_ps(t4 + 8)};
    compose(first, e, t, std::integral_constant<int, 0>{});
    if (count > 1) compose(first + 1, e, t, std::integral_constant<int, 1>{});
    if (count > 2) compose(first + 2, e, t, std::integral_constant<int, 2>{});
    if (count > 3) compose(first + 3, e, t, std::integral_constant<int, 3>{});
  };
  const glm::quat* rot = rotations.data();
  const float* trans = &translations.data()->x;
  for (; j + 4 <= end; j += 4) group(j, rot + j, trans + 3 * j, 4);
  if (j < end && j + 4 <= n) {
    // The last one to three joints of a range (partial updates are mostly such short runs: a
    // leg's hip and knee, an ankle and its toe) with the joints after them as padding: a lane
    // computes what the scalar loop would, in fewer instructions; the padding is not composed.
    group(j, rot + j, trans + 3 * j, end - j);
    j = end;
  } else if (j < end) {  // the skeleton's last joints: padded with identities past its end
    glm::quat tail_q[4] = {glm::quat(1, 0, 0, 0), glm::quat(1, 0, 0, 0), glm::quat(1, 0, 0, 0),
                           glm::quat(1, 0, 0, 0)};
    float tail_t[12] = {};
    std::copy(rot + j, rot + end, tail_q);
    std::copy(trans + 3 * j, trans + 3 * end, tail_t);
    group(j, tail_q, tail_t, end - j);
    j = end;
  }
#endif
  for (; j < end; ++j) {
    const int parent = skeleton->parents[j];
    fk::compose(parent < 0 ? root_transform : out_model[parent], rotations[j], translations[j],
                out_model[j]);
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

  // Current and desired interior angles, by their cosines (the rotations by their differences
  // need no angle: rotation_by_acos_difference).
  const glm::vec3 ab = glm::normalize(b - a), bc = glm::normalize(c - b);
  if (lac < 1e-6f) return;
  const glm::vec3 ac_n = ac / lac;
  const float cos_hip_0 = clamp_unit(glm::dot(ac_n, ab));
  const float cos_knee_0 = clamp_unit(glm::dot(-ab, bc));
  const float cos_hip_1 = clamp_unit((lcb * lcb - lab * lab - lat * lat) / (-2.0f * lab * lat));
  const float cos_knee_1 = clamp_unit((lat * lat - lab * lab - lcb * lcb) / (-2.0f * lab * lcb));

  // Bend plane normal: the current plane of the limb, or the pole plane when the limb is straight
  // or within 2 deg of it (its own plane may then point either way from frame to frame, and the
  // twist toward the pole would turn the limb about itself by up to half a turn).
  // In the pole's plane the limb's present bend counts by its share along that plane's normal
  // (negative when it bends away from the pole): continuous as the limb straightens.
  glm::vec3 axis0 = glm::cross(ac_n, ab);
  const float own = glm::length(axis0);
  const glm::vec3 pole_axis = glm::cross(ac_n, pole);
  const bool in_pole_plane = own < kStraightLimb && glm::length(pole_axis) >= 1e-5f;
  float along = 0.0f;
  if (in_pole_plane) {
    const glm::vec3 n = glm::normalize(pole_axis);
    along = own > 1e-9f ? glm::dot(axis0 / own, n) : 0.0f;
    axis0 = n;
  }
  if (glm::length(axis0) < 1e-5f) axis0 = glm::cross(ac_n, glm::vec3(1, 0, 0));
  axis0 = glm::normalize(axis0);

  glm::quat r_bend, r_knee;
  if (in_pole_plane) {  // the present bend scaled by its share: the angles themselves
    const float hip_0 = along * std::acos(cos_hip_0);
    const float knee_0 = kPi - along * (kPi - std::acos(cos_knee_0));
    r_bend = glm::angleAxis(std::acos(cos_hip_1) - hip_0, axis0);
    r_knee = glm::angleAxis(std::acos(cos_knee_1) - knee_0, axis0);
  } else {
    r_bend = rotation_by_acos_difference(cos_hip_1, cos_hip_0, axis0);
    r_knee = rotation_by_acos_difference(cos_knee_1, cos_knee_0, axis0);
  }
  // End joint after the bend, then swing the chain onto the target direction.
  const glm::vec3 c1 = a + r_bend * (b - a) + r_bend * (r_knee * (c - b));
  const glm::quat r_swing = rotation_between(c1 - a, target - a);
  glm::quat r = quat_mul(r_swing, r_bend);

  // Twist about the start-target axis so the knee points toward the pole.
  const glm::vec3 axis_t = glm::normalize(target - a);
  const glm::vec3 knee = r * (b - a);
  const glm::vec3 knee_p = knee - axis_t * glm::dot(knee, axis_t);
  const glm::vec3 pole_p = pole - axis_t * glm::dot(pole, axis_t);
  if (glm::length(knee_p) > 1e-5f && glm::length(pole_p) > 1e-5f) {
    r = quat_mul(rotation_of_cos_sin(glm::dot(knee_p, pole_p),
                                     glm::dot(glm::cross(knee_p, pole_p), axis_t), axis_t),
                 r);
  }

  const glm::quat qa = glm::quat_cast(glm::mat3(start_model));
  const glm::quat qb = glm::quat_cast(glm::mat3(mid_model));
  glm::quat start_corr = conjugate_into(qa, r);
  glm::quat mid_corr = conjugate_into(qb, r_knee);
  if (weight < 1.0f) {
    const glm::quat id(1, 0, 0, 0);
    start_corr = nlerp_shortest(id, start_corr, weight);
    mid_corr = nlerp_shortest(id, mid_corr, weight);
  }
  *out_start_correction = start_corr;
  *out_mid_correction = mid_corr;
}

#if defined(__SSE2__)
namespace {
namespace pair_ik {

// Three-vectors and quaternions of the two limbs, lanes (a, b, a, b): every lane glm's operations
// on its own limb in glm's order.
struct V3 {
  __m128 x, y, z;
};

inline __m128 splat(float v) { return _mm_set1_ps(v); }
inline __m128 pair(float a, float b) { return _mm_setr_ps(a, b, a, b); }
inline V3 pair(const glm::vec3& a, const glm::vec3& b) {
  return {pair(a.x, b.x), pair(a.y, b.y), pair(a.z, b.z)};
}
inline V3 sub(const V3& a, const V3& b) {
  return {_mm_sub_ps(a.x, b.x), _mm_sub_ps(a.y, b.y), _mm_sub_ps(a.z, b.z)};
}
inline V3 add(const V3& a, const V3& b) {
  return {_mm_add_ps(a.x, b.x), _mm_add_ps(a.y, b.y), _mm_add_ps(a.z, b.z)};
}
inline V3 scale(const V3& a, __m128 s) {
  return {_mm_mul_ps(a.x, s), _mm_mul_ps(a.y, s), _mm_mul_ps(a.z, s)};
}
inline V3 divide(const V3& a, __m128 s) {  // glm's v / s: each component divided
  return {_mm_div_ps(a.x, s), _mm_div_ps(a.y, s), _mm_div_ps(a.z, s)};
}
inline V3 negate(const V3& a) {
  const __m128 sign = splat(-0.0f);
  return {_mm_xor_ps(a.x, sign), _mm_xor_ps(a.y, sign), _mm_xor_ps(a.z, sign)};
}
// glm::dot: (xx + yy) + zz.
inline __m128 dot(const V3& a, const V3& b) {
  return _mm_add_ps(_mm_add_ps(_mm_mul_ps(a.x, b.x), _mm_mul_ps(a.y, b.y)), _mm_mul_ps(a.z, b.z));
}
inline V3 cross(const V3& x, const V3& y) {
  return {_mm_sub_ps(_mm_mul_ps(x.y, y.z), _mm_mul_ps(y.y, x.z)),
          _mm_sub_ps(_mm_mul_ps(x.z, y.x), _mm_mul_ps(y.z, x.x)),
          _mm_sub_ps(_mm_mul_ps(x.x, y.y), _mm_mul_ps(y.x, x.y))};
}
inline __m128 length(const V3& v) { return _mm_sqrt_ps(dot(v, v)); }
// glm::normalize: v * (1 / sqrt(dot(v, v))).
inline V3 normalize(const V3& v) { return scale(v, _mm_div_ps(splat(1.0f), length(v))); }
// std::max(a, b) and std::min(a, b) to the bit (ties and NaN: a): maxps / minps return their
// second operand then.
inline __m128 std_max(__m128 a, __m128 b) { return _mm_max_ps(b, a); }
inline __m128 std_min(__m128 a, __m128 b) { return _mm_min_ps(b, a); }
inline __m128 select(__m128 mask, __m128 a, __m128 b) {
  return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b));
}
// std::clamp(v, lo, hi): v < lo ? lo : hi < v ? hi : v.
inline __m128 clamp4(__m128 v, __m128 lo, __m128 hi) {
  return select(_mm_cmplt_ps(v, lo), lo, select(_mm_cmplt_ps(hi, v), hi, v));
}
inline __m128 clamp_unit4(__m128 x) { return clamp4(x, splat(-1.0f), splat(1.0f)); }
inline Quat4 select(__m128 mask, const Quat4& a, const Quat4& b) {
  return {select(mask, a.x, b.x), select(mask, a.y, b.y), select(mask, a.z, b.z),
          select(mask, a.w, b.w)};
}
inline bool any(__m128 mask) { return _mm_movemask_ps(mask) != 0; }

// glm's p * q.
inline Quat4 mul(const Quat4& p, const Quat4& q) {
  auto m = [](__m128 a, __m128 b) { return _mm_mul_ps(a, b); };
  return {_mm_sub_ps(_mm_add_ps(_mm_add_ps(m(p.w, q.x), m(p.x, q.w)), m(p.y, q.z)), m(p.z, q.y)),
          _mm_sub_ps(_mm_add_ps(_mm_add_ps(m(p.w, q.y), m(p.y, q.w)), m(p.z, q.x)), m(p.x, q.z)),
          _mm_sub_ps(_mm_add_ps(_mm_add_ps(m(p.w, q.z), m(p.z, q.w)), m(p.x, q.y)), m(p.y, q.x)),
          _mm_sub_ps(_mm_sub_ps(_mm_sub_ps(m(p.w, q.w), m(p.x, q.x)), m(p.y, q.y)), m(p.z, q.z))};
}
// glm::inverse: the conjugate over dot(q, q).
inline Quat4 inverse(const Quat4& q) {
  const __m128 n = dot4(q, q), sign = splat(-0.0f);
  return {_mm_div_ps(_mm_xor_ps(q.x, sign), n), _mm_div_ps(_mm_xor_ps(q.y, sign), n),
          _mm_div_ps(_mm_xor_ps(q.z, sign), n), _mm_div_ps(q.w, n)};
}
// glm's q * v.
inline V3 rotate(const Quat4& q, const V3& v) {
  const V3 qv{q.x, q.y, q.z};
  const V3 uv = cross(qv, v);
  const V3 uuv = cross(qv, uv);
  return add(v, scale(add(scale(uv, q.w), uuv), splat(2.0f)));
}

// rotation_of_cos_sin per lane; `fail` gets the lanes that would take its other branches.
inline Quat4 rotation_of_cos_sin(__m128 c, __m128 s, const V3& axis, __m128& fail) {
  const __m128 r = _mm_sqrt_ps(_mm_add_ps(_mm_mul_ps(c, c), _mm_mul_ps(s, s)));
  const __m128 rc = _mm_add_ps(r, c);
  fail = _mm_or_ps(_mm_cmpngt_ps(r, _mm_setzero_ps()),
                   _mm_cmplt_ps(rc, _mm_mul_ps(splat(1e-3f), r)));
  return normalize4({_mm_mul_ps(s, axis.x), _mm_mul_ps(s, axis.y), _mm_mul_ps(s, axis.z), rc});
}

// rotation_by_acos_difference per lane.
inline Quat4 rotation_by_acos_difference(__m128 c1, __m128 c0, const V3& axis) {
  const __m128 half = splat(0.5f), one = splat(1.0f), zero = _mm_setzero_ps();
  auto half_cos = [&](__m128 c) {
    return _mm_sqrt_ps(std_max(zero, _mm_mul_ps(half, _mm_add_ps(one, c))));
  };
  auto half_sin = [&](__m128 c) {
    return _mm_sqrt_ps(std_max(zero, _mm_mul_ps(half, _mm_sub_ps(one, c))));
  };
  const __m128 h1c = half_cos(c1), h1s = half_sin(c1), h0c = half_cos(c0), h0s = half_sin(c0);
  const __m128 cw = _mm_add_ps(_mm_mul_ps(h1c, h0c), _mm_mul_ps(h1s, h0s));
  const __m128 sw = _mm_sub_ps(_mm_mul_ps(h1s, h0c), _mm_mul_ps(h1c, h0s));
  return {_mm_mul_ps(sw, axis.x), _mm_mul_ps(sw, axis.y), _mm_mul_ps(sw, axis.z), cw};
}

// rotation_between per lane; `fail` gets the lanes of its degenerate branches.
inline Quat4 rotation_between(V3 from, V3 to, __m128& fail) {
  const __m128 lf = length(from), lt = length(to);
  const __m128 tiny = splat(1e-8f);
  fail = _mm_or_ps(_mm_cmplt_ps(lf, tiny), _mm_cmplt_ps(lt, tiny));
  from = divide(from, lf);
  to = divide(to, lt);
  const __m128 d = clamp_unit4(dot(from, to));
  const V3 axis = cross(from, to);
  const __m128 axis_len = length(axis);
  fail = _mm_or_ps(fail, _mm_cmplt_ps(axis_len, splat(1e-7f)));
  __m128 fail_cs;
  const Quat4 q = rotation_of_cos_sin(d, axis_len, divide(axis, axis_len), fail_cs);
  fail = _mm_or_ps(fail, fail_cs);
  return q;
}

// glm::quat_cast of four matrices' rotations (one per lane), its branches as selects.
inline Quat4 quat_cast4(const glm::mat4& m0, const glm::mat4& m1, const glm::mat4& m2,
                        const glm::mat4& m3) {
  __m128 col[3][4];
  for (int c = 0; c < 3; ++c) {
    col[c][0] = _mm_loadu_ps(&m0[c].x);
    col[c][1] = _mm_loadu_ps(&m1[c].x);
    col[c][2] = _mm_loadu_ps(&m2[c].x);
    col[c][3] = _mm_loadu_ps(&m3[c].x);
    _MM_TRANSPOSE4_PS(col[c][0], col[c][1], col[c][2], col[c][3]);  // col[c][r]: m[c][r]
  }
  auto m = [&](int c, int r) { return col[c][r]; };
  const __m128 fx = _mm_sub_ps(_mm_sub_ps(m(0, 0), m(1, 1)), m(2, 2));
  const __m128 fy = _mm_sub_ps(_mm_sub_ps(m(1, 1), m(0, 0)), m(2, 2));
  const __m128 fz = _mm_sub_ps(_mm_sub_ps(m(2, 2), m(0, 0)), m(1, 1));
  const __m128 fw = _mm_add_ps(_mm_add_ps(m(0, 0), m(1, 1)), m(2, 2));
  const __m128 is_x = _mm_cmpgt_ps(fx, fw);
  __m128 big = select(is_x, fx, fw);
  const __m128 is_y = _mm_cmpgt_ps(fy, big);
  big = select(is_y, fy, big);
  const __m128 is_z = _mm_cmpgt_ps(fz, big);
  big = select(is_z, fz, big);
  const __m128 bv = _mm_mul_ps(_mm_sqrt_ps(_mm_add_ps(big, splat(1.0f))), splat(0.5f));
  const __m128 mult = _mm_div_ps(splat(0.25f), bv);
  const __m128 A = _mm_mul_ps(_mm_sub_ps(m(1, 2), m(2, 1)), mult);
  const __m128 B = _mm_mul_ps(_mm_sub_ps(m(2, 0), m(0, 2)), mult);
  const __m128 C = _mm_mul_ps(_mm_sub_ps(m(0, 1), m(1, 0)), mult);
  const __m128 D = _mm_mul_ps(_mm_add_ps(m(0, 1), m(1, 0)), mult);
  const __m128 E = _mm_mul_ps(_mm_add_ps(m(2, 0), m(0, 2)), mult);
  const __m128 F = _mm_mul_ps(_mm_add_ps(m(1, 2), m(2, 1)), mult);
  Quat4 q{A, B, C, bv};                      // w largest
  q = select(is_x, Quat4{bv, D, E, A}, q);  // x
  q = select(is_y, Quat4{D, bv, F, B}, q);  // y
  q = select(is_z, Quat4{E, F, bv, C}, q);  // z
  return q;
}

}  // namespace pair_ik
}  // namespace
#endif

TwoBoneIKJob TwoBoneIKLimb::job() const {
  TwoBoneIKJob j;
  j.start_model = *start_model;
  j.mid_model = *mid_model;
  j.end_model = *end_model;
  j.target = target;
  j.pole = pole;
  j.max_extension = max_extension;
  j.soften = soften;
  j.out_start_correction = out_start_correction;
  j.out_mid_correction = out_mid_correction;
  return j;
}

void two_bone_ik_pair(const TwoBoneIKJob& ja, const TwoBoneIKJob& jb) {
  if (ja.out_reached || jb.out_reached || !(ja.weight == 1.0f) || !(jb.weight == 1.0f)) {
    ja.run();
    jb.run();
    return;
  }
  auto limb = [](const TwoBoneIKJob& j) {
    return TwoBoneIKLimb{&j.start_model,  &j.mid_model, &j.end_model,
                         j.target,        j.pole,       j.max_extension,
                         j.soften,        j.out_start_correction, j.out_mid_correction};
  };
  two_bone_ik_pair(limb(ja), limb(jb));
}

void two_bone_ik_pair(const TwoBoneIKLimb& ja, const TwoBoneIKLimb& jb) {
#if defined(__SSE2__)
  using namespace pair_ik;
  auto one_by_one = [&] {
    ja.job().run();
    jb.job().run();
  };
  const V3 a = pair(translation_of(*ja.start_model), translation_of(*jb.start_model));
  const V3 b = pair(translation_of(*ja.mid_model), translation_of(*jb.mid_model));
  const V3 c = pair(translation_of(*ja.end_model), translation_of(*jb.end_model));
  const V3 target = pair(ja.target, jb.target);
  const V3 pole = pair(ja.pole, jb.pole);
  const V3 ba = sub(b, a), cb = sub(c, b);
  const __m128 lab = length(ba), lcb = length(cb);
  if (any(_mm_or_ps(_mm_cmplt_ps(lab, splat(1e-6f)), _mm_cmplt_ps(lcb, splat(1e-6f))))) {
    return one_by_one();
  }
  const V3 ta = sub(target, a);
  const __m128 reach = length(ta);
  const __m128 max_len =
      _mm_mul_ps(_mm_add_ps(lab, lcb), pair(ja.max_extension, jb.max_extension));
  const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
  const __m128 min_len = _mm_add_ps(_mm_and_ps(_mm_sub_ps(lab, lcb), abs_mask), splat(1e-4f));
  const V3 ac = sub(c, a);
  const __m128 lac = length(ac);
  const __m128 soften =
      pair(std::clamp(ja.soften, 0.0f, 1.0f), std::clamp(jb.soften, 0.0f, 1.0f));
  const __m128 soft_start = std_max(_mm_mul_ps(max_len, soften), std_min(lac, max_len));
  const __m128 soft_span = _mm_sub_ps(max_len, soft_start);
  __m128 soft_reach = reach;
  const int soft = _mm_movemask_ps(_mm_and_ps(_mm_cmpgt_ps(soft_span, splat(1e-6f)),
                                              _mm_cmpgt_ps(reach, soft_start)));
  if (soft & 3) {  // the exp per lane, by the scalar code's own expression
    alignas(16) float st[4], sp[4], re[4];
    _mm_store_ps(st, soft_start);
    _mm_store_ps(sp, soft_span);
    _mm_store_ps(re, reach);
    for (int k = 0; k < 2; ++k) {
      if (soft & (1 << k)) re[k] = st[k] + sp[k] * (1.0f - std::exp(-(re[k] - st[k]) / sp[k]));
    }
    soft_reach = pair(re[0], re[1]);
  }
  const __m128 lat = clamp4(soft_reach, min_len, std_max(min_len, max_len));
  const V3 ab = normalize(ba), bc = normalize(cb);
  if (any(_mm_cmplt_ps(lac, splat(1e-6f)))) return one_by_one();
  const V3 ac_n = divide(ac, lac);
  const __m128 cos_hip_0 = clamp_unit4(dot(ac_n, ab));
  const __m128 cos_knee_0 = clamp_unit4(dot(negate(ab), bc));
  const __m128 lab2 = _mm_mul_ps(lab, lab), lcb2 = _mm_mul_ps(lcb, lcb), lat2 = _mm_mul_ps(lat, lat);
  const __m128 m2lab = _mm_mul_ps(splat(-2.0f), lab);
  const __m128 cos_hip_1 =
      clamp_unit4(_mm_div_ps(_mm_sub_ps(_mm_sub_ps(lcb2, lab2), lat2), _mm_mul_ps(m2lab, lat)));
  const __m128 cos_knee_1 =
      clamp_unit4(_mm_div_ps(_mm_sub_ps(_mm_sub_ps(lat2, lab2), lcb2), _mm_mul_ps(m2lab, lcb)));
  // A limb near straight bends in the pole's plane (acos of its angles): one by one.
  V3 axis0 = cross(ac_n, ab);
  const __m128 own = length(axis0);
  const V3 pole_axis = cross(ac_n, pole);
  if (any(_mm_and_ps(_mm_cmplt_ps(own, splat(kStraightLimb)),
                     _mm_cmpge_ps(length(pole_axis), splat(1e-5f)))) ||
      any(_mm_cmplt_ps(own, splat(1e-5f)))) {
    return one_by_one();
  }
  axis0 = normalize(axis0);
  const Quat4 r_bend = rotation_by_acos_difference(cos_hip_1, cos_hip_0, axis0);
  const Quat4 r_knee = rotation_by_acos_difference(cos_knee_1, cos_knee_0, axis0);
  const V3 c1 = add(add(a, rotate(r_bend, ba)), rotate(r_bend, rotate(r_knee, cb)));
  __m128 fail;
  const Quat4 r_swing = rotation_between(sub(c1, a), ta, fail);
  if (any(fail)) return one_by_one();
  Quat4 r = mul(r_swing, r_bend);
  const V3 axis_t = normalize(ta);
  const V3 knee = rotate(r, ba);
  const V3 knee_p = sub(knee, scale(axis_t, dot(knee, axis_t)));
  const V3 pole_p = sub(pole, scale(axis_t, dot(pole, axis_t)));
  const __m128 twist = _mm_and_ps(_mm_cmpgt_ps(length(knee_p), splat(1e-5f)),
                                  _mm_cmpgt_ps(length(pole_p), splat(1e-5f)));
  if (any(twist)) {
    const Quat4 t =
        rotation_of_cos_sin(dot(knee_p, pole_p), dot(cross(knee_p, pole_p), axis_t), axis_t, fail);
    if (any(_mm_and_ps(fail, twist))) return one_by_one();
    r = select(twist, mul(t, r), r);
  }
  // Lanes (a start, b start, a mid, b mid): conjugate_into of r and r_knee.
  const Quat4 q = quat_cast4(*ja.start_model, *jb.start_model, *ja.mid_model, *jb.mid_model);
  const __m128 mid_lanes = _mm_castsi128_ps(_mm_setr_epi32(0, 0, -1, -1));
  const Quat4 rr = select(mid_lanes, r_knee, r);
  glm::quat out[4];
  store4(normalize4(mul(mul(inverse(q), rr), q)), out);
  *ja.out_start_correction = out[0];
  *jb.out_start_correction = out[1];
  *ja.out_mid_correction = out[2];
  *jb.out_mid_correction = out[3];
#else
  ja.job().run();
  jb.job().run();
#endif
}

bool SkinningPaletteJob::validate() const {
  return model.size() == inverse_bind.size() && out_palette.size() >= model.size() &&
         (out_model_copy.empty() || out_model_copy.size() >= model.size());
}

void SkinningPaletteJob::run() const {
#if defined(__SSE2__)
  const bool fused_copy = !out_model_copy.empty() && affine_inverse_bind && stream_out &&
                          reinterpret_cast<uintptr_t>(out_palette.data()) % 16 == 0 &&
                          reinterpret_cast<uintptr_t>(out_model_copy.data()) % 16 == 0;
#else
  const bool fused_copy = false;
#endif
  if (!out_model_copy.empty() && !fused_copy) copy_matrices(model, out_model_copy, true);
  if (!affine_inverse_bind) {
    for (size_t j = 0; j < model.size(); ++j) out_palette[j] = model[j] * inverse_bind[j];
    return;
  }
#if defined(__SSE2__)
  if (!stream_out || reinterpret_cast<uintptr_t>(out_palette.data()) % 16 == 0) {
    // The arrays through locals: after a streamed store (may-alias) members would be read again.
    const float* a = &(*model.data())[0].x;
    const float* b = &(*inverse_bind.data())[0].x;
    float* m = &(*out_palette.data())[0].x;
    float* copy = fused_copy ? &(*out_model_copy.data())[0].x : nullptr;
    const float* const a_end = a + 16 * model.size();
    // One loop per case, streamed (with the copy or without) or cached, for any affine inverse
    // binds or translations only (the tests hoisted out of the joints' loop). The loop below's
    // sums in its order, four lanes at once: the same bits.
    auto palettes = [&](auto streamed, auto with_copy, auto translations)
                        __attribute__((always_inline)) {
      auto store = [](float* to, __m128 v) __attribute__((always_inline)) {
        if constexpr (decltype(streamed)::value) {
          _mm_stream_ps(to, v);
        } else {
          _mm_storeu_ps(to, v);
        }
      };
      for (; a != a_end; a += 16, b += 16, m += 16) {
        const __m128 a0 = _mm_loadu_ps(a), a1 = _mm_loadu_ps(a + 4), a2 = _mm_loadu_ps(a + 8),
                     a3 = _mm_loadu_ps(a + 12);
        if constexpr (decltype(with_copy)::value) {
          _mm_stream_ps(copy, a0);
          _mm_stream_ps(copy + 4, a1);
          _mm_stream_ps(copy + 8, a2);
          _mm_stream_ps(copy + 12, a3);
          copy += 16;
        }
        if constexpr (decltype(translations)::value) {
          store(m, a0);
          store(m + 4, a1);
          store(m + 8, a2);
        }
        for (int c = decltype(translations)::value ? 3 : 0; c < 4; ++c) {
          // The column loaded once, its entries broadcast from the register.
          const __m128 bc = _mm_loadu_ps(b + 4 * c);
          __m128 col = _mm_add_ps(_mm_add_ps(_mm_mul_ps(a0, broadcast_lane<0>(bc)),
                                             _mm_mul_ps(a1, broadcast_lane<1>(bc))),
                                  _mm_mul_ps(a2, broadcast_lane<2>(bc)));
          if (c == 3) col = _mm_add_ps(col, a3);
          store(m + 4 * c, col);
        }
      }
    };
    using yes = std::true_type;
    using no = std::false_type;
    if (!stream_out && translation_inverse_bind) {
      palettes(no{}, no{}, yes{});
    } else if (!stream_out) {
      palettes(no{}, no{}, no{});
    } else if (copy && translation_inverse_bind) {
      palettes(yes{}, yes{}, yes{});
    } else if (copy) {
      palettes(yes{}, yes{}, no{});
    } else if (translation_inverse_bind) {
      palettes(yes{}, no{}, yes{});
    } else {
      palettes(yes{}, no{}, no{});
    }
    if (stream_out && fence) stream_fence();
    return;
  }
#endif
  for (size_t j = 0; j < model.size(); ++j) {
    // As glm's product, leaving out the terms with the inverse bind's bottom-row zeros.
    const glm::mat4& a = model[j];
    const glm::mat4& b = inverse_bind[j];
    glm::mat4& m = out_palette[j];
    if (translation_inverse_bind) {
      m[0] = a[0];
      m[1] = a[1];
      m[2] = a[2];
    } else {
      m[0] = a[0] * b[0][0] + a[1] * b[0][1] + a[2] * b[0][2];
      m[1] = a[0] * b[1][0] + a[1] * b[1][1] + a[2] * b[1][2];
      m[2] = a[0] * b[2][0] + a[1] * b[2][1] + a[2] * b[2][2];
    }
    m[3] = a[0] * b[3][0] + a[1] * b[3][1] + a[2] * b[3][2] + a[3];
  }
}

void copy_matrices(std::span<const glm::mat4> from, std::span<glm::mat4> to, bool stream) {
#if defined(__SSE2__)
  if (stream && reinterpret_cast<uintptr_t>(to.data()) % 16 == 0) {
    const float* a = &(*from.data())[0].x;
    float* m = &(*to.data())[0].x;
    const float* const a_end = a + 16 * from.size();
    for (; a != a_end; a += 16, m += 16) {
      const __m128 c0 = _mm_loadu_ps(a), c1 = _mm_loadu_ps(a + 4), c2 = _mm_loadu_ps(a + 8),
                   c3 = _mm_loadu_ps(a + 12);
      _mm_stream_ps(m, c0);
      _mm_stream_ps(m + 4, c1);
      _mm_stream_ps(m + 8, c2);
      _mm_stream_ps(m + 12, c3);
    }
    return;
  }
#endif
  (void)stream;
  std::copy(from.begin(), from.end(), to.begin());
}

void stream_fence() {
#if defined(__SSE2__)
  _mm_sfence();  // the streamed stores are ordered before whatever tells a reader they are done
#endif
}

float min_abs_dot(std::span<const glm::quat> a, std::span<const glm::quat> b) {
  const size_t n = std::min(a.size(), b.size());
  float d_min = 1.0f;
  size_t j = 0;
#if defined(__SSE2__)
  if (n >= 4) {
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    __m128 m = _mm_set1_ps(1.0f);
    for (; j + 4 <= n; j += 4) {
      // min(x, m) keeps m where x is NaN, as std::min(m, x) does.
      m = _mm_min_ps(_mm_and_ps(dot4(load4(a.data() + j), load4(b.data() + j)), abs_mask), m);
    }
    alignas(16) float lanes[4];
    _mm_store_ps(lanes, m);
    d_min = std::min(std::min(lanes[0], lanes[1]), std::min(lanes[2], lanes[3]));
  }
#endif
  for (; j < n; ++j) d_min = std::min(d_min, std::abs(glm::dot(a[j], b[j])));
  return d_min;
}

float min_abs_dot_then_copy(std::span<const glm::quat> a, std::span<glm::quat> b) {
  const size_t n = std::min(a.size(), b.size());
  float d_min = 1.0f;
  size_t j = 0;
#if defined(__SSE2__)
  if (n >= 4) {  // min_abs_dot's loop, each group copied once it is read
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    __m128 m = _mm_set1_ps(1.0f);
    for (; j + 4 <= n; j += 4) {
      // a's four quaternions copied from the registers they are loaded into, before the transpose.
      const float* pa = &a[j].x;
      float* pb = &b[j].x;
      __m128 ax = _mm_loadu_ps(pa), ay = _mm_loadu_ps(pa + 4), az = _mm_loadu_ps(pa + 8),
             aw = _mm_loadu_ps(pa + 12);
      const Quat4 qb = load4(b.data() + j);
      _mm_storeu_ps(pb, ax);
      _mm_storeu_ps(pb + 4, ay);
      _mm_storeu_ps(pb + 8, az);
      _mm_storeu_ps(pb + 12, aw);
      _MM_TRANSPOSE4_PS(ax, ay, az, aw);
      m = _mm_min_ps(_mm_and_ps(dot4(Quat4{ax, ay, az, aw}, qb), abs_mask), m);
    }
    alignas(16) float lanes[4];
    _mm_store_ps(lanes, m);
    d_min = std::min(std::min(lanes[0], lanes[1]), std::min(lanes[2], lanes[3]));
  }
#endif
  for (; j < n; ++j) {
    d_min = std::min(d_min, std::abs(glm::dot(a[j], b[j])));
    b[j] = a[j];
  }
  return d_min;
}

bool is_translation(std::span<const glm::mat4> matrices) {
  if (!is_affine(matrices)) return false;
  for (const glm::mat4& m : matrices) {
    for (int c = 0; c < 3; ++c) {
      for (int r = 0; r < 3; ++r) {
        if (m[c][r] != (c == r ? 1.0f : 0.0f)) return false;
      }
    }
  }
  return true;
}

bool is_affine(std::span<const glm::mat4> matrices) {
  for (const glm::mat4& m : matrices) {
    if (m[0][3] != 0.0f || m[1][3] != 0.0f || m[2][3] != 0.0f || m[3][3] != 1.0f) return false;
  }
  return true;
}

}  // namespace gk
