#pragma once
// A crowd that starts again whenever every agent has left: it wraps a factory that builds the
// crowd of round k = 0, 1, 2, ... (for a scenario: its agents drawn with seed + k). While a round
// has agents, everything passes through; on the first step after a frame with none left, the next
// round is built and its first frame shown. Time keeps counting across rounds. With a scenario
// whose agents vanish at their goal (`"at_goal": "remove"`), agents keep entering and leaving for
// as long as it runs (bench/soak.sh). Ids repeat across rounds, but every agent has been absent
// for at least one frame before its id comes back, so a consumer sees a new agent.
//
// Building a round allocates (once per round, never per frame). A round must fit the capacity of
// the first; one that does not, or a factory error, fails step() with the factory's message.

#include <functional>
#include <memory>
#include <string>

#include "crowd/crowd_source.h"

namespace gk {

class RestartingCrowd final : public CrowdSource {
 public:
  using Factory = std::function<Result<std::unique_ptr<CrowdSource>>(int round)>;
  // Builds round 0.
  static Result<std::unique_ptr<RestartingCrowd>> create(Factory factory);

  std::string name() const override { return current_->name(); }
  Status step(float dt_s) override;
  AgentFrame frame() const override { return current_->frame(); }
  FeedbackPolicy feedback_policy() const override { return current_->feedback_policy(); }
  Status apply_feedback(const AgentFeedback& feedback) override {
    return current_->apply_feedback(feedback);
  }
  double time_s() const override { return round_start_s_ + current_->time_s(); }
  size_t capacity() const override { return capacity_; }
  // Rounds started so far (1 after create()).
  int rounds() const { return round_ + 1; }

 private:
  RestartingCrowd(Factory factory, std::unique_ptr<CrowdSource> first);
  Factory factory_;
  std::unique_ptr<CrowdSource> current_;
  size_t capacity_;
  int round_ = 0;
  bool round_had_agents_ = false;
  double round_start_s_ = 0.0;
};

}  // namespace gk
