// The heel-off pivot's bisection decided by the distance's closed form against the bisection that
// measures the distance at every step: the same pitch to the bit, and it brings the ankle within
// the limit.

#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "mediator/pose_synthesis.h"

namespace gk {
namespace {

TEST(HeelOffPivot, SameStepsAsTheMeasuredBisection) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), u01(0.0f, 1.0f);
  int pivoted = 0, partial = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    // A pinned toe on the floor, the ankle behind and above it (a flat to slightly raised foot),
    // the hip about a leg above and ahead of it, the limit a little short of the ankle's reach.
    const float yaw = 3.14159f * u(rng);
    const glm::vec3 fwd(std::sin(yaw), 0.0f, std::cos(yaw));
    const glm::vec3 toe(u(rng), 0.02f + 0.01f * u(rng), u(rng));
    const glm::vec3 ankle =
        toe - fwd * (0.12f + 0.04f * u01(rng)) + glm::vec3(0.0f, 0.06f + 0.08f * u01(rng), 0.0f);
    const glm::vec3 hip = ankle + fwd * (0.5f * u(rng)) +
                          glm::vec3(0.1f * u(rng), 0.75f + 0.1f * u(rng), 0.1f * u(rng));
    const float reach = glm::length(ankle - hip);
    const float limit = reach * (0.85f + 0.2f * u01(rng));
    const float fast = heel_off_pitch(toe, ankle, hip, limit);
    const float reference = heel_off_pitch(toe, ankle, hip, limit, /*closed_form=*/false);
    ASSERT_EQ(fast, reference) << "trial " << trial;
    if (fast > 0.0f) ++pivoted;
    // Short of the whole range (the toe -> ankle line at 1 rad), the pitched ankle is within the
    // limit: the bisection's upper end only ever moves to a pitch that is.
    const glm::vec3 d = ankle - toe;
    const float room = 1.0f - std::asin(d.y / glm::length(d));
    const glm::vec3 axis = glm::normalize(glm::cross(d, glm::vec3(0, 1, 0)));
    const glm::vec3 pitched = toe + glm::angleAxis(fast, axis) * d;
    if (fast < room - 1e-4f) {
      EXPECT_LE(glm::length(pitched - hip), limit) << "trial " << trial;
      if (glm::length(ankle - hip) > limit) ++partial;
    }
  }
  // The cases exercise the pivot, not only its trivial ends.
  EXPECT_GT(pivoted, 5000);
  EXPECT_GT(partial, 2000);
}

}  // namespace
}  // namespace gk
