#pragma once
// atan2() for four floats at once with SSE2 and no branch, for the angles the crowd commits every
// step: glibc's atan2f branches on the argument's range, and with walking directions spread all
// round those branches are unpredictable (about 13% of a 100k-agent step went there). Like exp4,
// the same instructions run on every x86-64; atan2_1() is lane 0 of it.
//
// Accuracy: at most 2 ulp from the correctly rounded atan2 (97% exact, 2 ulp only next to
// |y/x| = tan(pi/8); 2.2e9 pairs checked, tests/crowd/test_simd_atan2.cc samples them), so at
// most 3 ulp from glibc's atan2f; signed zeros as atan2 (atan2(+-0, -0) = +-pi); NaN in, NaN
// out; both arguments infinite gives NaN.
// |y| and |x| fold to an angle in [0, pi/4] and the argument is reduced once more by pi/4, to
// u in [-tan(pi/8), tan(pi/8)], with one division; atan(u) is Cephes' atanf polynomial and the
// result is C + S atan(u) with C a multiple of pi/4 held as two floats, so it is rounded once.

#include <emmintrin.h>

namespace gk {

inline __m128 atan2_4(__m128 y, __m128 x) {
  const __m128 sign = _mm_set1_ps(-0.0f);
  const __m128 ax = _mm_andnot_ps(sign, x), ay = _mm_andnot_ps(sign, y);
  const __m128 mx = _mm_max_ps(ax, ay), mn = _mm_min_ps(ax, ay);
  const __m128 steep = _mm_cmpgt_ps(ay, ax);  // angle measured from pi/2
  const __m128 big = _mm_cmpgt_ps(mn, _mm_mul_ps(_mm_set1_ps(0.414213568f), mx));  // > pi/8
  const __m128 neg_x = _mm_castsi128_ps(_mm_srai_epi32(_mm_castps_si128(x), 31));  // sign bit
  auto select = [](__m128 mask, __m128 a, __m128 b) {
    return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b));
  };
  // atan(mn / mx) = pi/4 + atan((mn - mx) / (mn + mx)) above tan(pi/8); 0 / 0 gives 0.
  const __m128 num = select(big, _mm_sub_ps(mn, mx), mn);
  const __m128 den = select(big, _mm_add_ps(mn, mx), mx);
  const __m128 u = _mm_and_ps(_mm_cmpneq_ps(den, _mm_setzero_ps()), _mm_div_ps(num, den));
  const __m128 z = _mm_mul_ps(u, u);
  __m128 p = _mm_set1_ps(8.05374449538e-2f);
  p = _mm_sub_ps(_mm_mul_ps(p, z), _mm_set1_ps(1.38776856032e-1f));
  p = _mm_add_ps(_mm_mul_ps(p, z), _mm_set1_ps(1.99777106478e-1f));
  p = _mm_sub_ps(_mm_mul_ps(p, z), _mm_set1_ps(3.33329491539e-1f));
  p = _mm_add_ps(_mm_mul_ps(_mm_mul_ps(p, z), u), u);
  // The first-quadrant angle is C + S p with (C, S) = (0 or pi/4, +1), or (pi/2 or pi/4, -1) when
  // steep; x < 0 turns it into pi - angle.
  const __m128 c_hi =
      select(big, select(neg_x, _mm_set1_ps(2.3561945f), _mm_set1_ps(0.785398185f)),
             select(steep, _mm_set1_ps(1.57079637f), _mm_and_ps(neg_x, _mm_set1_ps(3.14159274f))));
  const __m128 c_lo = select(
      big, select(neg_x, _mm_set1_ps(-5.96244032e-9f), _mm_set1_ps(-2.18556941e-8f)),
      select(steep, _mm_set1_ps(-4.37113883e-8f), _mm_and_ps(neg_x, _mm_set1_ps(-8.74227766e-8f))));
  const __m128 s = _mm_and_ps(_mm_xor_ps(steep, neg_x), sign);  // -0 where S = -1
  const __m128 angle = _mm_add_ps(c_hi, _mm_add_ps(c_lo, _mm_xor_ps(p, s)));
  const __m128 nan = _mm_cmpunord_ps(x, y);
  return _mm_or_ps(_mm_xor_ps(angle, _mm_and_ps(y, sign)), nan);
}

inline float atan2_1(float y, float x) {
  return _mm_cvtss_f32(atan2_4(_mm_set_ss(y), _mm_set_ss(x)));
}

}  // namespace gk
