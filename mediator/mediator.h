#pragma once
// The Animation Planning Mediator: between any CrowdSource and the pose output it decides, per
// agent and frame, which clips to play at what rate and blend, how the body is oriented, and what
// the simulator must be told so the two stay consistent (ARCHITECTURE.md, steps 1-6 and 8; step 7,
// foot locking, runs in the pose synthesis pass where the animated feet are known).
//
// All per-agent data lives in slots (structure of arrays) sized for the crowd's capacity at
// construction; plan() allocates nothing. It validates the frame, assigns slots, then runs the
// whole-crowd passes of mediator/mediator_passes.h in order (filter, root, facing, weights, rate
// and phase, transitions, contacts, feedback), each over every agent in parallel.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec2.hpp>

#include "crowd/crowd_source.h"
#include "mediator/animation_plans.h"
#include "mediator/id_map.h"
#include "mediator/locomotion_library.h"
#include "mediator/mediator_passes.h"
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
  // Last frame's support reach per slot (PoseSynthesizer::support_reach; empty: none): the rate
  // pass quickens the steps by it, and the root pass holds the root in it (support_hold) only if
  // `hold`, where the held position is fed back to a source. The span must stay valid while set.
  // CrowdPipeline sets it every frame; a Mediator driven without one gets neither.
  void set_support_reach(std::span<const SupportReach> by_slot, bool hold) {
    support_reach_ = by_slot;
    support_hold_allowed_ = hold;
  }

  const AnimationPlans& plans() const { return plans_; }
  const FeedbackBuffers& feedback() const { return feedback_; }
  size_t num_agents() const { return num_agents_; }
  size_t capacity() const { return capacity_; }
  const LocomotionLibrary& library() const { return library_; }
  // The parameters in effect: as given, except that apm with a library whose every gait clip is
  // doubtful (gait_analysis_doubtful) plays it as naive does (degraded()).
  const MediatorParams& params() const { return params_; }
  void set_params(const MediatorParams& p);
  bool degraded() const { return degraded_; }
  // Starts and stops seen since construction and how many played a transition clip (indexed by
  // TransitionCount; mediator_passes.h): summed over the slots.
  std::array<uint64_t, kNumCounts> transition_counts() const;
  // Per slot: the transition playing (index into library().transitions, -1: none), its clip time
  // [s] and layer weight.
  int transition_of_slot(int slot) const { return tr_index_[slot]; }
  float transition_time_of_slot(int slot) const { return tr_time_[slot]; }
  float transition_weight_of_slot(int slot) const { return tr_weight_[slot]; }
  // Agents whose input had to be sanitised (NaN or speeds above 15 m/s) since construction.
  uint64_t num_sanitised() const { return num_sanitised_; }
  // Sim-side velocity of agent i of the last frame (for the feedback metric).
  std::span<const glm::vec2> sim_velocities() const { return {sim_vel_.data(), num_agents_}; }

 private:
  // validate: the checks of plan(); writes only scratch (seen_, found_slot_, new_ids_, emptied
  // again).
  Status validate(const AgentFrame& frame, float dt_s);
  // slots: known agents keep their slots, vanished ones free theirs, newcomers are initialised.
  void assign_slots(const AgentFrame& frame);
  void init_slot(int slot, uint32_t id, const glm::vec2& p, const glm::vec2& v, float theta);
  // LOD: an agent that is not due this frame (set_lod_due) is advanced, not planned; the step a
  // due one is planned over (the time since its last plan).
  void advance_agent(int agent, int slot, const glm::vec2& p, const glm::vec2& v, float theta,
                     float dt, float pull);
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
  AnimationPlans plans_;             // also carries the gait phase from frame to frame
  FeedbackBuffers feedback_;
  // Per agent: the frame as sanitised by the filter pass.
  std::vector<glm::vec2> sim_pos_, sim_vel_;
  std::vector<float> sim_theta_;
  // Per slot, carried from frame to frame.
  std::vector<glm::vec2> vel_, vel_rate_;  // velocity spring
  std::vector<float> theta_, theta_rate_;  // theta spring (unwrapped)
  std::vector<glm::vec2> still_at_;        // where a standing agent stands (FilterState)
  std::vector<float> still_jitter2_;       // its p's mean square jitter there [m^2]
  std::vector<uint8_t> jitter_held_;       // held standing through it at the last plan (LOD
                                           // advance_agent reads it between plans)
  bool library_doubtful_ = false;          // gait_analysis_doubtful(library_), found once
  bool degraded_ = false;                  // apm asked, naive played (a doubtful library)
  std::vector<float> fed_speed_;           // the speed the simulator was last given [m/s]
  std::vector<float> lower_target_;        // target facing of the lower body
  std::vector<float> lower_yaw_rate_;      // its turn rate [rad/s]
  std::vector<float> clip_weights_;        // [slot * num_clips + clip]: faded weights
  std::vector<float> idle_time_;           // clock of the standing clip
  std::vector<float> cadence_scale_;       // per-agent variety
  std::vector<float> reach_boost_;         // rate pass, carried (ReachInput::boost)
  // Transitions (mediator_passes.h, TransitionState).
  std::vector<int16_t> tr_index_;
  std::vector<TransitionStage> tr_stage_;
  std::vector<float> tr_time_, tr_weight_, tr_rate_, tr_waited_, tr_min_cadence_, tr_chosen_speed_,
      tr_lag_, tr_prev_speed_, tr_prev_phase_;
  std::vector<float> tr_still_, tr_moving_, tr_peak_speed_;
  std::vector<uint8_t> tr_start_due_;
  std::vector<uint32_t> tr_counts_;  // [slot * kNumCounts + k]
  // Per slot, scratch between passes.
  std::vector<float> root_heading_;    // root pass -> facing pass
  std::vector<float> rel_dir_;         // facing pass -> weights pass
  std::vector<float> scratch_target_;  // [slot * num_clips]: the weights pass's target weights
  // LOD, per slot: whether it is planned this frame, the step it is planned over [s], and the
  // time [s], phase and root advance since its last plan.
  std::span<const uint8_t> lod_due_;
  std::span<const SupportReach> support_reach_;
  bool support_hold_allowed_ = false;
  bool jitter_gate_was_on_ = false;  // stand_through_jitter acted in the last plan
  std::vector<glm::vec2> hold_;
  std::vector<float> hold_scale_;
  std::vector<float> root_speed_;  // the drawn root's speed last frame [m/s]
  std::vector<uint8_t> lod_plan_;
  std::vector<float> lod_dt_s_;
  std::vector<float> lod_elapsed_s_, lod_phase_advance_, lod_tr_advance_;
  // LOD: per slot, the gait cycles per second of its last plan's layers (gait_frequency; 0 without
  // a gait clip), kept for the advance between plans; valid once planned with LOD on.
  std::vector<float> lod_cycles_per_s_;
  std::vector<uint8_t> lod_cycles_valid_;
  bool lod_was_on_ = false;
  std::vector<glm::vec2> lod_root_at_plan_;
};

}  // namespace gk
