// atan2_4/atan2_1 (crowd/simd_atan2.h) against the correctly rounded atan2 and std::atan2: every
// 37th float ratio from 2^-30 to 2^30 in all four quadrants, random pairs, and the special values.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include <gtest/gtest.h>

#include "crowd/simd_atan2.h"
#include "tests/crowd/float_ulps.h"

namespace gk {
namespace {

using test::from_bits;
using test::ordered;
using test::ulps;


TEST(SimdAtan2, WithinTwoUlpOverAllQuadrants) {
  int64_t checked = 0, worst = 0, worst_lib = 0;
  float worst_y = 0.0f, worst_x = 0.0f;
  auto check = [&](float y, float x) {  // no gtest macro per pair: millions of them
    const float got = atan2_1(y, x);
    const float exact = static_cast<float>(std::atan2(double(y), double(x)));
    if (const int64_t u = ulps(got, exact); u > worst) worst = u, worst_y = y, worst_x = x;
    worst_lib = std::max(worst_lib, ulps(got, std::atan2(y, x)));
    ++checked;
  };
  for (uint32_t b = 0x30800000u; b <= 0x4e800000u; b += 37) {  // 2^-30 .. 2^30
    const float t = from_bits(b);
    check(t, 1.0f), check(-t, -1.0f), check(1.0f, -t), check(-1.0f, t);
  }
  uint64_t state = 5;
  for (int i = 0; i < 2'000'000; ++i) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const float y = std::ldexp(float(int32_t(state >> 32)), -int((state >> 8) % 40));
    const float x = std::ldexp(float(int32_t(state)), -int((state >> 16) % 40));
    check(y, x);
  }
  EXPECT_GT(checked, 50'000'000);
  EXPECT_LE(worst, 2) << "y = " << worst_y << ", x = " << worst_x;
  EXPECT_LE(worst_lib, 3);
}

TEST(SimdAtan2, SpecialValues) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  constexpr float kPi = 3.14159274f;  // pi rounded to float, as atan2f gives it
  EXPECT_EQ(ordered(atan2_1(0.0f, 0.0f)), ordered(0.0f));
  EXPECT_EQ(ordered(atan2_1(-0.0f, 0.0f)), ordered(-0.0f));
  EXPECT_EQ(atan2_1(0.0f, -0.0f), kPi);
  EXPECT_EQ(atan2_1(-0.0f, -0.0f), -kPi);
  EXPECT_EQ(atan2_1(0.0f, -1.0f), kPi);
  EXPECT_EQ(atan2_1(1.0f, 0.0f), std::atan2(1.0f, 0.0f));
  EXPECT_EQ(atan2_1(-1.0f, -0.0f), std::atan2(-1.0f, -0.0f));
  EXPECT_EQ(atan2_1(kInf, 1.0f), std::atan2(kInf, 1.0f));
  EXPECT_EQ(atan2_1(1.0f, -kInf), kPi);
  EXPECT_EQ(atan2_1(1.0f, 1.0f), std::atan2(1.0f, 1.0f));
  EXPECT_TRUE(std::isnan(atan2_1(std::numeric_limits<float>::quiet_NaN(), 1.0f)));
  EXPECT_TRUE(std::isnan(atan2_1(1.0f, std::numeric_limits<float>::quiet_NaN())));
}

TEST(SimdAtan2, LanesAreIndependentOfEachOther) {
  const float vs[] = {-3.0f, -1e-3f, -0.0f, 0.0f, 2e-5f, 0.4142f, 1.0f, 7.5f};
  for (float y : vs) {
    for (float x : vs) {
      alignas(16) float out[4];
      _mm_store_ps(out, atan2_4(_mm_setr_ps(y, x, -y, 2.0f), _mm_setr_ps(x, y, 1.0f, x)));
      EXPECT_EQ(ordered(out[0]), ordered(atan2_1(y, x)));
      EXPECT_EQ(ordered(out[1]), ordered(atan2_1(x, y)));
      EXPECT_EQ(ordered(out[2]), ordered(atan2_1(-y, 1.0f)));
      EXPECT_EQ(ordered(out[3]), ordered(atan2_1(2.0f, x)));
    }
  }
}

}  // namespace
}  // namespace gk
