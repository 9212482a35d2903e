// Simulator garbage through the whole pipeline (plan, feedback, pose synthesis with skinning
// palettes, metrics): NaN, infinities, 1e30, 1 km teleports, 1,000 m/s and agents whose very
// first frame is garbage. Nothing of it may reach a palette, a plan field or a flagged feedback
// value.

#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "crowd/crowd_source.h"
#include "mediator/metrics.h"
#include "mediator/pose_synthesis.h"
#include "tests/mediator/mediator_fixture.h"

namespace gk {
namespace {

constexpr float kDt = 1.0f / 60.0f;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// Eight agents walking along +z; on scheduled frames each gets one kind of garbage. Feedback is
// honoured (so whatever the mediator sends back is fed to the next frame).
class GarbageCrowd : public CrowdSource {
 public:
  GarbageCrowd() {
    for (uint32_t i = 0; i < kAgents; ++i) {
      ids_[i] = 100 + i;
      p_[i] = glm::vec2(2.0f * i, 0.0f);
      v_[i] = glm::vec2(0.0f, 1.3f);
      th_[i] = 0.0f;
    }
  }
  std::string name() const override { return "garbage"; }
  // The first step makes frame 0 (the agents where they start); each later one moves them on.
  Status step(float dt) override {
    const bool first = ++frame_ == 0;
    for (uint32_t i = 0; i < kAgents; ++i) {
      // The clean state of each agent moves on; garbage is laid over it afresh each frame.
      if (!first) clean_p_[i] += clean_v_[i] * dt;
      p_[i] = clean_p_[i];
      v_[i] = clean_v_[i];
      th_[i] = clean_th_[i];
    }
    spoil();
    return Status::Ok();
  }
  AgentFrame frame() const override { return {ids_, p_, v_, th_}; }
  FeedbackPolicy feedback_policy() const override { return FeedbackPolicy::kHonoured; }
  Status apply_feedback(const AgentFeedback& fb) override {
    for (uint32_t i = 0; i < kAgents; ++i) {
      if (!fb.has_feedback[i]) continue;
      ++feedback_count_;
      // Honoured only where finite: the test checks finiteness separately.
      if (std::isfinite(fb.velocities[i].x) && std::isfinite(fb.velocities[i].y)) {
        clean_v_[i] = fb.velocities[i];
      }
      if (std::isfinite(fb.thetas[i])) clean_th_[i] = fb.thetas[i];
    }
    return Status::Ok();
  }
  double time_s() const override { return frame_ * kDt; }
  size_t capacity() const override { return kAgents; }
  int64_t feedback_count() const { return feedback_count_; }

  static constexpr uint32_t kAgents = 8;

 private:
  void spoil() {
    const int f = frame_;
    const bool burst = (f >= 60 && f < 90) || (f >= 200 && f < 203);
    // Agent 0: NaN position, velocity and theta; 1: infinities; 2: 1e30; 3: a 1 km teleport each
    // burst frame; 4: 1,000 m/s; 5: garbage on its very first frame only, then clean; 6: garbage
    // on every frame; 7: clean throughout.
    if (burst) {
      p_[0] = {kNaN, kNaN}, v_[0] = {kNaN, 0.0f}, th_[0] = kNaN;
      p_[1] = {kInf, -kInf}, v_[1] = {kInf, kInf}, th_[1] = -kInf;
      p_[2] = {1e30f, 1e30f}, v_[2] = {1e30f, -1e30f}, th_[2] = 1e30f;
      p_[3] += glm::vec2(1000.0f, (f % 2 ? 1000.0f : -1000.0f));
      v_[4] = {0.0f, 1000.0f};
    }
    if (f == 0) p_[5] = {kNaN, kInf}, v_[5] = {1e30f, kNaN}, th_[5] = kInf;
    p_[6] = {kNaN, 1e30f}, v_[6] = {kInf, kNaN}, th_[6] = kNaN;
  }

  uint32_t ids_[kAgents];
  glm::vec2 p_[kAgents], v_[kAgents];
  float th_[kAgents];
  glm::vec2 clean_p_[kAgents] = {{0, 0}, {2, 0}, {4, 0}, {6, 0}, {8, 0}, {10, 0}, {12, 0}, {14, 0}};
  glm::vec2 clean_v_[kAgents] = {{0, 1.3f}, {0, 1.3f}, {0, 1.3f}, {0, 1.3f},
                                 {0, 1.3f}, {0, 1.3f}, {0, 1.3f}, {0, 1.3f}};
  float clean_th_[kAgents] = {};
  int frame_ = -1;  // before the first step
  int64_t feedback_count_ = 0;
};

bool finite(const glm::vec2& v) { return std::isfinite(v.x) && std::isfinite(v.y); }

TEST(Garbage, NothingFromTheSimulatorReachesPalettesPlansOrFeedback) {
  const LocomotionLibrary& lib = test::builtin_library();
  GarbageCrowd crowd;
  PipelineOptions options = test::test_pipeline_options(GarbageCrowd::kAgents, kDt);
  options.make_palettes = true;
  CrowdPipeline pipeline(lib, MediatorParams{}, options);
  const Mediator& mediator = pipeline.mediator();
  const PoseSynthesizer& poses = pipeline.poses();
  int bad_palette = 0, bad_plan = 0, bad_feedback = 0;
  for (int f = 0; f < 300; ++f) {
    ASSERT_TRUE(pipeline.step(crowd, kDt).ok()) << "frame " << f;
    pipeline.update_palettes();
    const AgentFrame frame = pipeline.frame();
    const AnimationPlans& pl = mediator.plans();
    for (size_t i = 0; i < frame.size(); ++i) {
      const int slot = pl.slot_of_agent[i];
      ASSERT_GE(slot, 0);
      for (const glm::mat4& m : poses.palette(slot)) {
        for (int c = 0; c < 4; ++c) {
          for (int r = 0; r < 4; ++r) bad_palette += !std::isfinite(m[c][r]);
        }
      }
      bad_plan += !finite(pl.root_xz[slot]) + !std::isfinite(pl.lower_yaw[slot]) +
                  !std::isfinite(pl.upper_yaw[slot]) + !std::isfinite(pl.travel_yaw[slot]) +
                  !std::isfinite(pl.playback_rate[slot]) + !std::isfinite(pl.speed_m_s[slot]) +
                  !std::isfinite(pl.phase[slot]);
      for (int k = 0; k < kMaxBlendLayers; ++k) {
        bad_plan += !std::isfinite(pl.layer_weight[slot * kMaxBlendLayers + k]) +
                    !std::isfinite(pl.layer_time_s[slot * kMaxBlendLayers + k]);
      }
      const FeedbackBuffers& fb = mediator.feedback();
      if (fb.has_feedback[i]) {
        bad_feedback +=
            !finite(fb.positions[i]) + !finite(fb.velocities[i]) + !std::isfinite(fb.thetas[i]);
      }
    }
  }
  EXPECT_EQ(bad_palette, 0);
  EXPECT_EQ(bad_plan, 0);
  EXPECT_EQ(bad_feedback, 0);
  // The garbage was seen and sanitised (agents 0-2, 4, 5 and 6 at least), not silently absent.
  EXPECT_GE(mediator.num_sanitised(), 6u);
  // The metrics stay numbers: the clean agent and the sanitised ones are still measured.
  const MetricsReport r = pipeline.metrics()->finish();
  EXPECT_TRUE(std::isfinite(r.root_error_cm.mean));
  EXPECT_TRUE(std::isfinite(r.feet.support_slide_cm_s));
  EXPECT_TRUE(std::isfinite(r.feet.limb_pop_rate));
  EXPECT_TRUE(std::isfinite(r.max_root_jerk));
}

}  // namespace
}  // namespace gk
