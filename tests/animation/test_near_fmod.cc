#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "animation/near_fmod.h"

namespace gk {
namespace {

// The same bits as std::fmod (signed zeros, NaN as NaN).
bool same_as_fmod(float x, float y) {
  const float got = near_fmod(x, y), want = std::fmod(x, y);
  if (std::isnan(want)) return std::isnan(got);
  return std::bit_cast<uint32_t>(got) == std::bit_cast<uint32_t>(want);
}

TEST(NearFmod, TheSameBitsAsFmod) {
  // The periods the per-frame code wraps by: a gait phase, a full turn, clips' frame counts.
  const float periods[] = {1.0f, 2.0f * std::numbers::pi_v<float>, 31.0f, 96.0f, 1e-3f};
  std::mt19937 rng(5);
  for (const float y : periods) {
    // Around and within the shortcut's range (-y, 2y), its edges, and far beyond it.
    std::uniform_real_distribution<float> near(-3.0f * y, 3.0f * y);
    std::uniform_real_distribution<float> far(-1e4f * y, 1e4f * y);
    for (int i = 0; i < 200000; ++i) {
      const float x = near(rng);
      ASSERT_TRUE(same_as_fmod(x, y)) << x << " mod " << y;
      const float z = far(rng);
      ASSERT_TRUE(same_as_fmod(z, y)) << z << " mod " << y;
    }
    for (const float x : {0.0f, -0.0f, y, -y, 2.0f * y, -2.0f * y, std::nextafter(y, 0.0f),
                          std::nextafter(2.0f * y, 0.0f), std::nextafter(-y, 0.0f),
                          std::nextafter(y, 3.0f * y), std::numeric_limits<float>::denorm_min(),
                          std::numeric_limits<float>::infinity(),
                          -std::numeric_limits<float>::infinity(),
                          std::numeric_limits<float>::quiet_NaN()}) {
      EXPECT_TRUE(same_as_fmod(x, y)) << x << " mod " << y;
    }
  }
}

}  // namespace
}  // namespace gk
