#pragma once
// exp() for four floats at once with SSE2 only, for the social-force kernels: the library's
// expf is scalar, and which of its variants runs depends on the CPU (glibc picks an FMA one
// where it can). This one is the same instruction sequence on every x86-64, so a lane's result
// does not depend on the machine, on the other lanes or on how neighbours are grouped; exp1()
// is lane 0 of it, for the scalar paths.
//
// Accuracy: at most 1 ulp from the correctly rounded exp for every float argument (checked
// exhaustively: 99.2% exact, and never more than 1 ulp from glibc's expf, subnormal results
// included; tests/crowd/test_simd_exp.cc samples it); +inf above ln(FLT_MAX), 0 below -103.97,
// NaN stays NaN.
// The argument is reduced by n ln2 (Cody-Waite, n*kLn2Hi exact for |n| < 2^15) to |r| <= ln2/2
// and exp(r) is Cephes' degree-7 polynomial; 2^n is applied as two factors so that neither
// overflows before the product does and a subnormal result is rounded only by the last multiply.

#include <emmintrin.h>

namespace gk {

inline __m128 exp4(__m128 x) {
  const __m128 nan = _mm_cmpunord_ps(x, x);
  // Outside this range the result is 0 or +inf anyway; clamping keeps n within the exponent.
  x = _mm_min_ps(_mm_max_ps(x, _mm_set1_ps(-104.0f)), _mm_set1_ps(89.0f));
  const __m128i n = _mm_cvtps_epi32(_mm_mul_ps(x, _mm_set1_ps(1.44269504088896341f)));
  const __m128 fn = _mm_cvtepi32_ps(n);
  __m128 r = _mm_sub_ps(x, _mm_mul_ps(fn, _mm_set1_ps(0.693359375f)));  // kLn2Hi: exact
  r = _mm_sub_ps(r, _mm_mul_ps(fn, _mm_set1_ps(-2.12194440e-4f)));      // kLn2Lo
  __m128 p = _mm_set1_ps(1.9875691500e-4f);
  p = _mm_add_ps(_mm_mul_ps(p, r), _mm_set1_ps(1.3981999507e-3f));
  p = _mm_add_ps(_mm_mul_ps(p, r), _mm_set1_ps(8.3334519073e-3f));
  p = _mm_add_ps(_mm_mul_ps(p, r), _mm_set1_ps(4.1665795894e-2f));
  p = _mm_add_ps(_mm_mul_ps(p, r), _mm_set1_ps(1.6666665459e-1f));
  p = _mm_add_ps(_mm_mul_ps(p, r), _mm_set1_ps(5.0000001201e-1f));
  p = _mm_add_ps(_mm_add_ps(_mm_mul_ps(p, _mm_mul_ps(r, r)), r), _mm_set1_ps(1.0f));
  // 2^n = 2^n1 2^n2 with n1 = n >> 1 (n in [-150, 129]): both factors are normal floats.
  const __m128i n1 = _mm_srai_epi32(n, 1);
  const __m128i n2 = _mm_sub_epi32(n, n1);
  const __m128i bias = _mm_set1_epi32(127);
  const __m128 s1 = _mm_castsi128_ps(_mm_slli_epi32(_mm_add_epi32(n1, bias), 23));
  const __m128 s2 = _mm_castsi128_ps(_mm_slli_epi32(_mm_add_epi32(n2, bias), 23));
  return _mm_or_ps(_mm_mul_ps(_mm_mul_ps(p, s1), s2), nan);
}

inline float exp1(float x) { return _mm_cvtss_f32(exp4(_mm_set_ss(x))); }

}  // namespace gk
