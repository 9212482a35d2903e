// exp4/exp1 (crowd/simd_exp.h) against the correctly rounded exp and against std::exp: every
// 61st float from -110 to 100 (the exhaustive run behind the header's figures takes a minute),
// the edges of overflow and underflow, and the arguments the social force produces.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include <gtest/gtest.h>

#include "crowd/simd_exp.h"
#include "tests/crowd/float_ulps.h"

namespace gk {
namespace {

using test::from_bits;
using test::ulps;

float correctly_rounded_exp(float x) { return static_cast<float>(std::exp(double(x))); }

void expect_close(float x) {
  const float got = exp1(x);
  EXPECT_LE(ulps(got, correctly_rounded_exp(x)), 1) << "x = " << x;
  EXPECT_LE(ulps(got, std::exp(x)), 1) << "x = " << x;
}

TEST(SimdExp, WithinOneUlpOverTheWholeRange) {
  int64_t checked = 0, worst = 0, worst_lib = 0;
  float worst_x = 0.0f, worst_lib_x = 0.0f;
  auto check = [&](float x) {  // no gtest macro per float: 36 million of them
    const float got = exp1(x);
    if (const int64_t u = ulps(got, correctly_rounded_exp(x)); u > worst) worst = u, worst_x = x;
    if (const int64_t u = ulps(got, std::exp(x)); u > worst_lib) worst_lib = u, worst_lib_x = x;
    ++checked;
  };
  for (uint32_t b = 0; from_bits(b) <= 100.0f; b += 61) check(from_bits(b));
  for (uint32_t b = 0x80000000u; from_bits(b) >= -110.0f; b += 61) check(from_bits(b));
  EXPECT_GT(checked, 30'000'000);
  EXPECT_LE(worst, 1) << "x = " << worst_x;
  EXPECT_LE(worst_lib, 1) << "x = " << worst_lib_x;
}

TEST(SimdExp, EdgesAndSpecialValues) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  EXPECT_EQ(exp1(0.0f), 1.0f);
  EXPECT_EQ(exp1(-0.0f), 1.0f);
  EXPECT_EQ(exp1(kInf), kInf);
  EXPECT_EQ(exp1(-kInf), 0.0f);
  EXPECT_TRUE(std::isnan(exp1(std::numeric_limits<float>::quiet_NaN())));
  EXPECT_EQ(exp1(std::numeric_limits<float>::max()), kInf);
  EXPECT_EQ(exp1(-std::numeric_limits<float>::max()), 0.0f);
  EXPECT_EQ(exp1(88.73f), kInf);    // past ln(FLT_MAX) = 88.7228
  EXPECT_EQ(exp1(-103.98f), 0.0f);  // below ln(2^-150): rounds to zero
  EXPECT_GT(exp1(-103.2f), 0.0f);   // a subnormal
  for (float x : {88.72f, 88.7228f, -87.33f, -87.34f, -100.0f, -103.2f, 1e-8f, -1e-8f}) {
    expect_close(x);
  }
}

// The repulsion's argument (r_i + r_j - b) / B lies in about [-2700, 40] for the parameter
// limits; every lane of exp4 equals exp1 of it whatever its neighbours hold.
TEST(SimdExp, LanesAreIndependentOfEachOther) {
  const float xs[] = {-2700.0f, -40.0f, -3.5f, -0.25f, 0.0f, 0.4f, 5.7f, 40.0f};
  for (float a : xs) {
    for (float b : xs) {
      alignas(16) float out[4];
      _mm_store_ps(out, exp4(_mm_setr_ps(a, b, -a, 0.5f * b)));
      EXPECT_EQ(out[0], exp1(a));
      EXPECT_EQ(out[1], exp1(b));
      EXPECT_EQ(out[2], exp1(-a));
      EXPECT_EQ(out[3], exp1(0.5f * b));
      expect_close(a);
    }
  }
}

}  // namespace
}  // namespace gk
