// RestartingCrowd: a new round when everyone has left, with one empty frame between rounds, time
// counting on, and a round too big or a factory error reported by step().

#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "crowd/restarting_crowd.h"

namespace gk {
namespace {

// `n` agents with ids 0..n-1; agent i leaves after i + 1 steps.
class Leaving final : public CrowdSource {
 public:
  explicit Leaving(size_t n)
      : ids_(n), pos_(n, glm::vec2(0.0f)), vel_(n, glm::vec2(0.0f)), theta_(n, 0.0f), live_(n) {
    for (size_t i = 0; i < n; ++i) ids_[i] = static_cast<uint32_t>(i);
  }
  std::string name() const override { return "leaving"; }
  Status step(float dt_s) override {
    time_s_ += dt_s;
    ++steps_;
    live_ = ids_.size() > steps_ ? ids_.size() - steps_ : 0;
    return Status::Ok();
  }
  // The agents still here are the last `live_` ids.
  AgentFrame frame() const override {
    const size_t first = ids_.size() - live_;
    return {{ids_.data() + first, live_},
            {pos_.data() + first, live_},
            {vel_.data() + first, live_},
            {theta_.data() + first, live_}};
  }
  FeedbackPolicy feedback_policy() const override { return FeedbackPolicy::kIgnored; }
  Status apply_feedback(const AgentFeedback&) override { return Status::Ok(); }
  double time_s() const override { return time_s_; }
  size_t capacity() const override { return ids_.size(); }

 private:
  std::vector<uint32_t> ids_;
  std::vector<glm::vec2> pos_, vel_;
  std::vector<float> theta_;
  size_t live_ = 0, steps_ = 0;
  double time_s_ = 0.0;
};

TEST(RestartingCrowd, NewRoundAfterOneEmptyFrame) {
  std::vector<int> built;
  auto crowd = RestartingCrowd::create([&](int round) -> Result<std::unique_ptr<CrowdSource>> {
    built.push_back(round);
    return std::unique_ptr<CrowdSource>(new Leaving(3));
  });
  ASSERT_TRUE(crowd.ok()) << crowd.message();
  RestartingCrowd& c = **crowd;
  EXPECT_EQ(c.capacity(), 3u);
  std::vector<size_t> sizes{c.frame().size()};
  for (int k = 0; k < 9; ++k) {
    ASSERT_TRUE(c.step(0.5f).ok());
    sizes.push_back(c.frame().size());
  }
  // 3, 2, 1, 0 (everyone left), then the next round's first frame: 3, 2, 1, 0, 3, ...
  EXPECT_EQ(sizes, (std::vector<size_t>{3, 2, 1, 0, 3, 2, 1, 0, 3, 2}));
  EXPECT_EQ(built, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(c.rounds(), 3);
  EXPECT_DOUBLE_EQ(c.time_s(), 4.5);  // nine steps of 0.5 s, across the rounds
}

TEST(RestartingCrowd, ReportsAFactoryErrorAndARoundTooBig) {
  auto failing = RestartingCrowd::create([](int round) -> Result<std::unique_ptr<CrowdSource>> {
    if (round > 0) return Status::Error("scenario.json: groups[0]: no room for the agents");
    return std::unique_ptr<CrowdSource>(new Leaving(1));
  });
  ASSERT_TRUE(failing.ok());
  ASSERT_TRUE((*failing)->step(0.1f).ok());  // the one agent leaves
  const Status s = (*failing)->step(0.1f);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("no room"), std::string::npos) << s.message();

  auto growing = RestartingCrowd::create([](int round) -> Result<std::unique_ptr<CrowdSource>> {
    return std::unique_ptr<CrowdSource>(new Leaving(1 + static_cast<size_t>(round)));
  });
  ASSERT_TRUE(growing.ok());
  ASSERT_TRUE((*growing)->step(0.1f).ok());
  const Status big = (*growing)->step(0.1f);
  EXPECT_FALSE(big.ok());
  EXPECT_NE(big.message().find("more than the 1 of the first"), std::string::npos) << big.message();
}

}  // namespace
}  // namespace gk
