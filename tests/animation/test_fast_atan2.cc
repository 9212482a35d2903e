#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "animation/fast_atan2.h"

namespace gk {
namespace {

// The documented bound [rad], against atan2 in double of the same float arguments.
constexpr double kBound = 3e-7;

double error_of(float y, float x) {
  return std::abs(static_cast<double>(fast_atan2(y, x)) -
                  std::atan2(static_cast<double>(y), static_cast<double>(x)));
}

TEST(FastAtan2, WithinItsBoundAllRoundTheCircle) {
  // Every direction, finely: each octant, its folds at tan(pi/8) and 1, and the wrap at +-pi.
  double worst = 0.0;
  for (int k = 0; k <= 720000; ++k) {
    const double a = -M_PI + 2.0 * M_PI * k / 720000.0;
    const float y = static_cast<float>(std::sin(a)), x = static_cast<float>(std::cos(a));
    worst = std::max(worst, error_of(y, x));
  }
  EXPECT_LE(worst, kBound);
  EXPECT_GT(worst, 0.0);  // not libm in disguise: a different, polynomial result
}

TEST(FastAtan2, WithinItsBoundAtAnyScaleAndRatio) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::uniform_real_distribution<float> exponent(-30.0f, 30.0f);
  double worst = 0.0;
  for (int i = 0; i < 400000; ++i) {
    const float scale = std::exp2(exponent(rng));
    const float y = unit(rng) * scale * (i % 3 == 0 ? 1e-4f : 1.0f);
    const float x = unit(rng) * scale * (i % 5 == 0 ? 1e4f : 1.0f);
    worst = std::max(worst, error_of(y, x));
  }
  EXPECT_LE(worst, kBound);
}

TEST(FastAtan2, SpecialValuesAsStdAtan2) {
  const float inf = std::numeric_limits<float>::infinity();
  const float cases[][2] = {{0.0f, 0.0f},   {-0.0f, 0.0f}, {0.0f, -0.0f}, {-0.0f, -0.0f},
                            {1.0f, 0.0f},   {-1.0f, 0.0f}, {0.0f, 1.0f},  {0.0f, -1.0f},
                            {-0.0f, -1.0f}, {inf, 1.0f},   {1.0f, -inf},  {-inf, inf},
                            {2.0f, 2.0f},   {-3.0f, -3.0f}};
  for (const auto& c : cases) {
    const float got = fast_atan2(c[0], c[1]), want = std::atan2(c[0], c[1]);
    EXPECT_NEAR(got, want, kBound) << c[0] << ", " << c[1];
    EXPECT_EQ(std::signbit(got), std::signbit(want)) << c[0] << ", " << c[1];
  }
  EXPECT_TRUE(std::isnan(fast_atan2(std::nanf(""), 1.0f)));
  EXPECT_TRUE(std::isnan(fast_atan2(1.0f, std::nanf(""))));
}

}  // namespace
}  // namespace gk
