#include <cstring>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "animation/quat_sse.h"

namespace gk {
namespace {

bool same_bits(const glm::quat& a, const glm::quat& b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Unit quaternions, scaled ones and a few with zeros and signed zeros in them.
glm::quat random_quat(std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::uniform_int_distribution<int> kind(0, 5);
  glm::quat q(u(rng), u(rng), u(rng), u(rng));
  switch (kind(rng)) {
    case 0:
      return glm::normalize(q);
    case 1:
      return q * 37.5f;
    case 2:
      q.y = 0.0f;
      q.z = -0.0f;
      return q;
    default:
      return q;
  }
}

TEST(QuatSse, ProductIsGlmsToTheBit) {
  std::mt19937 rng(7);
  for (int i = 0; i < 200000; ++i) {
    const glm::quat p = random_quat(rng), q = random_quat(rng);
    ASSERT_TRUE(same_bits(quat_mul(p, q), p * q)) << i;
  }
}

TEST(QuatSse, ConjugationIsGlmsToTheBit) {
  std::mt19937 rng(11);
  for (int i = 0; i < 200000; ++i) {
    const glm::quat q = random_quat(rng), r = random_quat(rng);
    ASSERT_TRUE(same_bits(conjugate_into(q, r), glm::normalize(glm::inverse(q) * r * q))) << i;
  }
}

TEST(QuatSse, NormalizedProductsAreGlmsToTheBit) {
  std::mt19937 rng(13);
  for (int i = 0; i < 200000; ++i) {
    const glm::quat p = random_quat(rng), q = random_quat(rng);
    ASSERT_TRUE(same_bits(normalized_product(p, q), glm::normalize(p * q))) << i;
    ASSERT_TRUE(same_bits(normalized_inverse_product(p, q), glm::normalize(glm::inverse(p) * q)))
        << i;
  }
}

TEST(QuatSse, DegenerateInputsAsGlm) {
  const glm::quat zero(0, 0, 0, 0), id(1, 0, 0, 0), r(0.5f, 0.5f, -0.5f, 0.5f);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const glm::quat with_nan(nan, 0, 0, 1);
  // An all-zero q: its inverse is NaN, the product NaN and normalisation keeps it (as glm's).
  const glm::quat a = conjugate_into(zero, r), b = glm::normalize(glm::inverse(zero) * r * zero);
  EXPECT_EQ(std::isnan(a.w), std::isnan(b.w));
  // Tiny r: its length underflows to 0 and normalisation gives the identity.
  const glm::quat tiny(1e-30f, 0, 0, 0);
  EXPECT_TRUE(same_bits(conjugate_into(id, tiny), glm::normalize(glm::inverse(id) * tiny * id)));
  EXPECT_TRUE(std::isnan(quat_mul(with_nan, r).w));
  EXPECT_TRUE(std::isnan((with_nan * r).w));
}

}  // namespace
}  // namespace gk
