// The per-frame rule for the simulators: applying feedback allocates nothing (an error message is
// built only when there is an error).

#include <vector>

#include <gtest/gtest.h>

#include "crowd/scenario.h"
#include "crowd/social_forces.h"
#include "tests/pipeline/allocation_counter.h"
#include "tests/test_data.h"

namespace gk {
namespace {

TEST(SocialForcesFeedback, ApplyingFeedbackAllocatesNothing) {
  auto loaded = load_scenario_by_name("corridor", scenario_dir());
  ASSERT_TRUE(loaded.ok()) << loaded.message();
  const Scenario s = scale_scenario(*loaded, 20);
  auto agents = expand_agents(s, 20, 1);
  ASSERT_TRUE(agents.ok()) << agents.message();
  auto sim = SocialForces::create(s, *agents, SocialForceParams{});
  ASSERT_TRUE(sim.ok()) << sim.message();
  SocialForces& crowd = **sim;
  for (int f = 0; f < 10; ++f) ASSERT_TRUE(crowd.step(1.0f / 60.0f).ok());
  const AgentFrame frame = crowd.frame();
  const size_t n = frame.size();
  ASSERT_GT(n, 0u);
  // Every agent fed back: a little slower, facing where it goes.
  std::vector<uint8_t> has(n, 1);
  std::vector<glm::vec2> p(frame.positions.begin(), frame.positions.end());
  std::vector<glm::vec2> v(n);
  std::vector<float> theta(frame.thetas.begin(), frame.thetas.end());
  for (size_t i = 0; i < n; ++i) v[i] = 0.9f * frame.velocities[i];
  const AgentFeedback fb{has, p, v, theta};
  const int64_t before = test::allocations_so_far();
  for (int f = 0; f < 10; ++f) ASSERT_TRUE(crowd.apply_feedback(fb).ok());
  EXPECT_EQ(test::allocations_so_far() - before, 0);
  // And a bad value is still refused with a message naming the agent.
  v[0] = glm::vec2(1e6f, 0.0f);
  const Status bad = crowd.apply_feedback(AgentFeedback{has, p, v, theta});
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("agent id"), std::string::npos) << bad.message();
}

}  // namespace
}  // namespace gk
