#pragma once
// The Animation Planning Mediator: between any CrowdSource and the pose output it decides, per
// agent and frame, which clips to play at what rate and blend, how the body is oriented, and what
// the simulator must be told so the two stay consistent (ARCHITECTURE.md, steps 1-6 and 8; step 7,
// foot locking, runs in the pose synthesis pass where the animated feet are known).
//
// All per-agent data lives in slots (structure of arrays) sized for the crowd's capacity at
// construction; plan() allocates nothing and runs over agents in parallel.

#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec2.hpp>

#include "crowd/crowd_source.h"
#include "mediator/animation_plans.h"
#include "mediator/id_map.h"
#include "mediator/locomotion_library.h"
#include "mediator/params.h"

namespace gk {

// Feedback for the simulator, index-aligned with the last AgentFrame.
struct FeedbackBuffers {
  std::vector<uint8_t> has_feedback;
  std::vector<glm::vec2> positions;
  std::vector<glm::vec2> velocities;
  std::vector<float> thetas;
  AgentFeedback view(size_t n) const {
    return {{has_feedback.data(), n},
            {positions.data(), n},
            {velocities.data(), n},
            {thetas.data(), n}};
  }
};

class Mediator {
 public:
  Mediator(const LocomotionLibrary& library, const MediatorParams& params, size_t capacity);

  // Plans every live agent of the frame for a step of dt_s [s]. The frame is validated first (dt,
  // array lengths, capacity, ids neither reserved nor repeated): an error writes nothing, so the
  // previous plans, feedback and slots stay as they were. Bad simulator values (NaN, absurd
  // speeds) are not errors: they are sanitised per agent and counted, never propagated. A source
  // that ignores feedback (recorded data) is asked for none: feedback() then holds the frame's own
  // values, unflagged.
  Status plan(const AgentFrame& frame, float dt_s,
              FeedbackPolicy policy = FeedbackPolicy::kHonoured);

  // Level of detail (pipeline/lod.h): from the next plan() on, only the slots whose flag is set
  // (and fresh agents) are planned; the others keep their clips, blend and facing while their
  // phase and clip times advance with the planned rate and their root follows the simulator, and
  // they get no feedback. A planned agent's springs, fades and turn limits then step over the
  // whole time since its last plan. Empty (the default): every agent every frame. The span must
  // stay valid (capacity long) while it is set.
  void set_lod_due(std::span<const uint8_t> due_by_slot) { lod_due_ = due_by_slot; }

  const AnimationPlans& plans() const { return plans_; }
  const FeedbackBuffers& feedback() const { return feedback_; }
  size_t num_agents() const { return num_agents_; }
  size_t capacity() const { return capacity_; }
  const LocomotionLibrary& library() const { return library_; }
  const MediatorParams& params() const { return params_; }
  void set_params(const MediatorParams& p) { params_ = p; }
  // Agents whose input had to be sanitised (NaN or speeds above 15 m/s) since construction.
  uint64_t num_sanitised() const { return num_sanitised_; }
  // Sim-side velocity of agent i of the last frame (for the feedback metric).
  std::span<const glm::vec2> sim_velocities() const { return {sim_vel_.data(), num_agents_}; }

 private:
  // The checks of plan(); writes only scratch (seen_, found_slot_, new_ids_, emptied again).
  Status validate(const AgentFrame& frame, float dt_s);
  void init_slot(int slot, uint32_t id, const glm::vec2& p, const glm::vec2& v, float theta);
  void plan_agent(int agent, int slot, const glm::vec2& p, const glm::vec2& v, float theta,
                  float dt, bool feedback);
  void choose_weights(int slot, float speed, float rel_dir, float* out_w) const;
  // LOD: an agent that is not due (set_lod_due), and the step of one that is.
  void advance_agent(int agent, int slot, const glm::vec2& p, const glm::vec2& v, float theta,
                     float dt);
  float lod_step(int slot, float dt);

  const LocomotionLibrary& library_;
  MediatorParams params_;
  size_t capacity_;
  size_t num_agents_ = 0;
  uint64_t num_sanitised_ = 0;
  IdSlotMap ids_;
  std::vector<uint32_t> slot_id_;
  std::vector<uint8_t> seen_;
  std::vector<int32_t> found_slot_;  // scratch of validate(): agent -> known slot, or -1
  IdSlotMap new_ids_;                // scratch of validate(): the frame's newcomers
  AnimationPlans plans_;
  FeedbackBuffers feedback_;
  std::vector<glm::vec2> sim_vel_;
  // Per-slot state.
  std::vector<glm::vec2> vel_, vel_rate_;  // velocity spring
  std::vector<float> theta_, theta_rate_;  // theta spring (unwrapped)
  std::vector<float> lower_target_;        // discrete target facing of the lower body
  std::vector<float> clip_weights_;        // [slot * num_clips + clip]: faded weights
  std::vector<float> phase_;               // gait phase
  std::vector<float> idle_time_;           // clock of the standing clip
  std::vector<float> cadence_scale_;       // per-agent variety
  std::vector<float> fade_;                // blend progress
  std::vector<int16_t> dominant_;          // clip with the largest target weight
  std::vector<float> scratch_target_;      // [slot * num_clips]
  // LOD, per slot: time [s], phase and root advance since the slot's last plan.
  std::span<const uint8_t> lod_due_;
  std::vector<float> lod_elapsed_s_, lod_phase_advance_;
  std::vector<glm::vec2> lod_root_at_plan_;
};

}  // namespace gk
