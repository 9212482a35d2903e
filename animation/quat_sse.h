#pragma once
// glm's quaternion product, inverse and normalisation on one SSE register (x, y, z, w lanes, glm's
// storage order), for the few quaternions two-bone IK combines per leg: the scalar code spends
// most of its instructions on copies between registers. Every lane does glm's operations in its
// order (a - b as a + (-b), products negated exactly), so the results are the same bits
// (tests/animation/test_quat_sse.cc). Without SSE2 the glm functions themselves.

#include <glm/gtc/quaternion.hpp>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace gk {

#if defined(__SSE2__)
namespace quat_sse {

inline __m128 load(const glm::quat& q) { return _mm_loadu_ps(&q.x); }
inline glm::quat store(__m128 v) {
  glm::quat q;
  _mm_storeu_ps(&q.x, v);
  return q;
}

// Lanes (a, b, c, d) of v, by index (one pshufd).
template <int a, int b, int c, int d>
inline __m128 lanes(__m128 v) {
  return _mm_castsi128_ps(_mm_shuffle_epi32(_mm_castps_si128(v), _MM_SHUFFLE(d, c, b, a)));
}

// glm's p * q: w = ((pw qw - px qx) - py qy) - pz qz, x = ((pw qx + px qw) + py qz) - pz qy, and
// so on; the w lane's two subtractions as additions of negated products.
inline __m128 mul(__m128 p, __m128 q) {
  const __m128 w_neg = _mm_castsi128_ps(_mm_set_epi32(static_cast<int>(0x80000000u), 0, 0, 0));
  const __m128 t1 = _mm_mul_ps(lanes<3, 3, 3, 3>(p), q);
  const __m128 t2 = _mm_mul_ps(_mm_xor_ps(lanes<0, 1, 2, 0>(p), w_neg), lanes<3, 3, 3, 0>(q));
  const __m128 t3 = _mm_mul_ps(_mm_xor_ps(lanes<1, 2, 0, 1>(p), w_neg), lanes<2, 0, 1, 1>(q));
  const __m128 t4 = _mm_mul_ps(lanes<2, 0, 1, 2>(p), lanes<1, 2, 0, 2>(q));
  return _mm_sub_ps(_mm_add_ps(_mm_add_ps(t1, t2), t3), t4);
}

// glm::dot(q, q), (ww + xx) + (yy + zz), in every lane.
inline __m128 norm2(__m128 q) {
  const __m128 sq = _mm_mul_ps(q, q);
  const __m128 pairs = _mm_add_ps(sq, lanes<3, 2, 1, 0>(sq));  // xx + ww, yy + zz, ...
  return _mm_add_ps(pairs, lanes<1, 0, 3, 2>(pairs));
}

// glm::inverse: the conjugate over dot(q, q).
inline __m128 inverse(__m128 q) {
  const __m128 xyz_neg = _mm_castsi128_ps(_mm_set_epi32(0, static_cast<int>(0x80000000u),
                                                        static_cast<int>(0x80000000u),
                                                        static_cast<int>(0x80000000u)));
  return _mm_div_ps(_mm_xor_ps(q, xyz_neg), norm2(q));
}

// glm::normalize: q / |q| (times the reciprocal, as glm), the identity when |q| <= 0.
inline __m128 normalize(__m128 q) {
  const __m128 len = _mm_sqrt_ps(norm2(q));
  if (_mm_cvtss_f32(len) <= 0.0f) return _mm_setr_ps(0.0f, 0.0f, 0.0f, 1.0f);
  return _mm_mul_ps(q, _mm_div_ps(_mm_set1_ps(1.0f), len));
}

// glm::mat3_cast's nine entries (m[0][0], m[0][1], m[0][2], m[1][0], ..., column by column) of
// four quaternions, one per lane of x, y, z, w: each lane glm's operations in its order (FK).
inline void rotation_entries4(__m128 x, __m128 y, __m128 z, __m128 w, __m128 e[9]) {
  const __m128 one = _mm_set1_ps(1.0f), two = _mm_set1_ps(2.0f);
  const __m128 xx = _mm_mul_ps(x, x), yy = _mm_mul_ps(y, y), zz = _mm_mul_ps(z, z);
  const __m128 xz = _mm_mul_ps(x, z), xy = _mm_mul_ps(x, y), yz = _mm_mul_ps(y, z);
  const __m128 wx = _mm_mul_ps(w, x), wy = _mm_mul_ps(w, y), wz = _mm_mul_ps(w, z);
  e[0] = _mm_sub_ps(one, _mm_mul_ps(two, _mm_add_ps(yy, zz)));
  e[1] = _mm_mul_ps(two, _mm_add_ps(xy, wz));
  e[2] = _mm_mul_ps(two, _mm_sub_ps(xz, wy));
  e[3] = _mm_mul_ps(two, _mm_sub_ps(xy, wz));
  e[4] = _mm_sub_ps(one, _mm_mul_ps(two, _mm_add_ps(xx, zz)));
  e[5] = _mm_mul_ps(two, _mm_add_ps(yz, wx));
  e[6] = _mm_mul_ps(two, _mm_add_ps(xz, wy));
  e[7] = _mm_mul_ps(two, _mm_sub_ps(yz, wx));
  e[8] = _mm_sub_ps(one, _mm_mul_ps(two, _mm_add_ps(xx, yy)));
}

}  // namespace quat_sse
#endif

// glm::normalize(glm::inverse(q) * r * q): r seen from the frame q turns into (the world-space
// rotation r as a local correction of a joint whose world rotation is q).
inline glm::quat conjugate_into(const glm::quat& q, const glm::quat& r) {
#if defined(__SSE2__)
  using namespace quat_sse;
  const __m128 vq = load(q);
  return store(normalize(mul(mul(inverse(vq), load(r)), vq)));
#else
  return glm::normalize(glm::inverse(q) * r * q);
#endif
}

// glm::normalize(p * q): a rotation composed and kept unit length.
inline glm::quat normalized_product(const glm::quat& p, const glm::quat& q) {
#if defined(__SSE2__)
  using namespace quat_sse;
  return store(normalize(mul(load(p), load(q))));
#else
  return glm::normalize(p * q);
#endif
}

// glm::normalize(glm::inverse(p) * q).
inline glm::quat normalized_inverse_product(const glm::quat& p, const glm::quat& q) {
#if defined(__SSE2__)
  using namespace quat_sse;
  return store(normalize(mul(inverse(load(p)), load(q))));
#else
  return glm::normalize(glm::inverse(p) * q);
#endif
}

// glm's p * q.
inline glm::quat quat_mul(const glm::quat& p, const glm::quat& q) {
#if defined(__SSE2__)
  return quat_sse::store(quat_sse::mul(quat_sse::load(p), quat_sse::load(q)));
#else
  return p * q;
#endif
}

}  // namespace gk
