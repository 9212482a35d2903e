#pragma once
// atan2 without libm, for the headings pose synthesis takes several times per agent and frame
// (libm's atan2f was about a tenth of the pose stage).

#include <cmath>
#include <limits>

namespace gk {

// atan2(y, x) [rad], in [-pi, pi], within 3e-7 rad of the exact angle, as close as libm's atan2f
// (2.5e-7 with glibc; tests/animation/test_fast_atan2.cc), in about half its time. The octant
// is folded onto |t| <= tan(pi/8) (t = r, or (r - 1) / (r + 1) plus pi/4, for r = min / max of
// |x|, |y|: one division either way), where an odd polynomial of degree 9 (fitted for this, by
// weighted least squares toward minimax) is within 5e-9 rad of atan; the rest is float rounding,
// largest near pi. Zero, infinite and NaN arguments go to std::atan2 (its results, signed zeros
// and all).
inline float fast_atan2(float y, float x) {
  constexpr float kMax = std::numeric_limits<float>::max();
  constexpr float kTanPi8 = 0.41421356237f;
  constexpr float kPi = 3.14159265358979f, kHalfPi = 1.57079632679490f;
  constexpr float kQuarterPi = 0.78539816339745f;
  const float ax = std::abs(x), ay = std::abs(y);
  if (!(ax <= kMax && ay <= kMax) || (ax == 0.0f && ay == 0.0f)) return std::atan2(y, x);
  const float hi = ax > ay ? ax : ay, lo = ax > ay ? ay : ax;
  float t, base;
  if (lo > kTanPi8 * hi) {
    t = (lo - hi) / (lo + hi);  // (r - 1) / (r + 1) in (-tan(pi/8), 0]
    base = kQuarterPi;
  } else {
    t = lo / hi;
    base = 0.0f;
  }
  const float z = t * t;
  const float p = -0.33332756633f +
                  z * (0.19971878271f + z * (-0.13824444678f + z * 0.07902573118f));
  float v = base + (t + t * z * p);
  if (ay > ax) v = kHalfPi - v;
  if (std::signbit(x)) v = kPi - v;
  return std::copysign(v, y);
}

}  // namespace gk
