#pragma once
// A CrowdSource whose agents follow scripted velocity and theta functions of time: straight walks,
// speed ramps, turns on the spot, looking aside. Positions integrate the velocities exactly, so the
// expected root path is known independently of the mediator (a crowd that honours feedback takes
// the fed-back position, velocity and theta, as a simulator does).

#include <functional>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "crowd/crowd_source.h"

namespace gk::test {

struct Script {
  glm::vec2 start{0.0f};
  std::function<glm::vec2(double t)> velocity;
  std::function<float(double t, glm::vec2 v)> theta;  // default: heading of v
};

class ScriptedCrowd : public CrowdSource {
 public:
  explicit ScriptedCrowd(std::vector<Script> scripts, bool honour_feedback = false)
      : scripts_(std::move(scripts)), honour_(honour_feedback) {
    const size_t n = scripts_.size();
    ids_.resize(n);
    p_.resize(n);
    v_.resize(n);
    th_.resize(n);
    for (size_t i = 0; i < n; ++i) {
      ids_[i] = static_cast<uint32_t>(i * 7 + 3);
      p_[i] = scripts_[i].start;
      fill(i);
    }
  }
  std::string name() const override { return "scripted"; }
  Status step(float dt) override {
    for (size_t i = 0; i < scripts_.size(); ++i) p_[i] += v_[i] * dt;
    t_ += dt;
    for (size_t i = 0; i < scripts_.size(); ++i) fill(i);
    return Status::Ok();
  }
  AgentFrame frame() const override { return {ids_, p_, v_, th_}; }
  FeedbackPolicy feedback_policy() const override {
    return honour_ ? FeedbackPolicy::kHonoured : FeedbackPolicy::kIgnored;
  }
  Status apply_feedback(const AgentFeedback& fb) override {
    last_feedback_count_ = 0;
    for (size_t i = 0; i < ids_.size(); ++i) {
      if (!fb.has_feedback[i]) continue;
      ++last_feedback_count_;
      if (honour_) {
        p_[i] = fb.positions[i];
        v_[i] = fb.velocities[i];
        th_[i] = fb.thetas[i];
      }
    }
    return Status::Ok();
  }
  double time_s() const override { return t_; }
  size_t capacity() const override { return scripts_.size(); }
  int last_feedback_count() const { return last_feedback_count_; }

 private:
  void fill(size_t i) {
    v_[i] = scripts_[i].velocity(t_);
    th_[i] = scripts_[i].theta
                 ? scripts_[i].theta(t_, v_[i])
                 : (glm::length(v_[i]) > 1e-4f ? std::atan2(v_[i].x, v_[i].y) : th_[i]);
  }
  std::vector<Script> scripts_;
  bool honour_;
  double t_ = 0.0;
  std::vector<uint32_t> ids_;
  std::vector<glm::vec2> p_, v_;
  std::vector<float> th_;
  int last_feedback_count_ = 0;
};

}  // namespace gk::test
