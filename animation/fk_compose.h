#pragma once
// One joint's model matrix from its parent's and its local rotation and translation, as glm's
// parent * local with the products of the local matrix's zeros left out (glm's sums in its order:
// the same bits). Shared by the forward-kinematics jobs over joint ranges (LocalToModelJob) and
// joint lists (LocalToModelListJob).

#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

namespace gk::fk {

// m = p * [mat3_cast(q) t; 0 1].
inline void compose(const glm::mat4& p, const glm::quat& q, const glm::vec3& t, glm::mat4& m) {
  const glm::mat3 r = glm::mat3_cast(q);
  m[0] = p[0] * r[0][0] + p[1] * r[0][1] + p[2] * r[0][2];
  m[1] = p[0] * r[1][0] + p[1] * r[1][1] + p[2] * r[1][2];
  m[2] = p[0] * r[2][0] + p[1] * r[2][1] + p[2] * r[2][2];
  m[3] = p[0] * t.x + p[1] * t.y + p[2] * t.z + p[3];
}

#if defined(__SSE2__)
// The same from the parent's 16 floats `p`, the rotation's nine entries r[i] (column-major, each
// broadcast to all four lanes) and the translation's x, y, z (broadcast), into the 16 floats `m`.
inline __attribute__((always_inline)) void compose(const float* p, const __m128* r, __m128 tx,
                                                   __m128 ty, __m128 tz, float* m) {
  const __m128 p0 = _mm_loadu_ps(p), p1 = _mm_loadu_ps(p + 4), p2 = _mm_loadu_ps(p + 8),
               p3 = _mm_loadu_ps(p + 12);
  auto column = [&](__m128 a, __m128 b, __m128 c) {
    return _mm_add_ps(_mm_add_ps(_mm_mul_ps(p0, a), _mm_mul_ps(p1, b)), _mm_mul_ps(p2, c));
  };
  _mm_storeu_ps(m, column(r[0], r[1], r[2]));
  _mm_storeu_ps(m + 4, column(r[3], r[4], r[5]));
  _mm_storeu_ps(m + 8, column(r[6], r[7], r[8]));
  _mm_storeu_ps(m + 12, _mm_add_ps(column(tx, ty, tz), p3));
}
#endif

}  // namespace gk::fk
