#include "mediator/mediator.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <random>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "animation/near_fmod.h"
#include "mediator/mediator_passes.h"

namespace gk {

Mediator::Mediator(const LocomotionLibrary& library, const MediatorParams& params, size_t capacity)
    : library_(library),
      params_(params),
      capacity_(capacity),
      ids_(capacity),
      library_doubtful_(gait_analysis_doubtful(library)) {
  set_params(params);
  const size_t nc = library.clips.size();
  const size_t L = capacity * kMaxBlendLayers;
  slot_id_.assign(capacity, 0xffffffffu);
  seen_.assign(capacity, 0);
  found_slot_.assign(capacity, -1);
  new_ids_.reset(capacity);
  plans_.slot_of_agent.assign(capacity, -1);
  plans_.gait_weight.assign(capacity, 0.0f);
  plans_.agent_of_slot.assign(capacity, -1);
  plans_.layer_clip.assign(L, 0);
  plans_.layer_weight.assign(L, 0.0f);
  plans_.layer_time_s.assign(L, 0.0f);
  plans_.root_xz.assign(capacity, glm::vec2(0.0f));
  hold_.assign(capacity, glm::vec2(0.0f));
  hold_scale_.assign(capacity, 1.0f);
  root_speed_.assign(capacity, 0.0f);
  plans_.lower_yaw.assign(capacity, 0.0f);
  plans_.upper_yaw.assign(capacity, 0.0f);
  plans_.travel_yaw.assign(capacity, 0.0f);
  plans_.playback_rate.assign(capacity, 1.0f);
  plans_.speed_m_s.assign(capacity, 0.0f);
  for (int s = 0; s < 2; ++s) {
    plans_.plant[s].assign(capacity, 1.0f);
    plans_.hold[s].assign(capacity, 1.0f);
    plans_.gait_toe_y[s].assign(capacity, 0.0f);
    plans_.stand_toe_y[s].assign(capacity, std::numeric_limits<float>::lowest());
    plans_.clip_toe_speed[s].assign(capacity, -1.0f);
    plans_.swing_progress[s].assign(capacity, 0.0f);
    plans_.landing_s[s].assign(capacity, -1.0f);
    plans_.double_support.assign(capacity, 0.0f);
  }
  plans_.phase.assign(capacity, 0.0f);
  plans_.blend_progress.assign(capacity, 1.0f);
  plans_.standing.assign(capacity, 1);
  plans_.standing_votes.assign(capacity, 1);
  plans_.fresh.assign(capacity, 1);
  feedback_.has_feedback.assign(capacity, 0);
  feedback_.positions.assign(capacity, glm::vec2(0.0f));
  feedback_.velocities.assign(capacity, glm::vec2(0.0f));
  feedback_.thetas.assign(capacity, 0.0f);
  sim_pos_.assign(capacity, glm::vec2(0.0f));
  sim_vel_.assign(capacity, glm::vec2(0.0f));
  sim_theta_.assign(capacity, 0.0f);
  vel_.assign(capacity, glm::vec2(0.0f));
  vel_rate_.assign(capacity, glm::vec2(0.0f));
  fed_speed_.assign(capacity, 0.0f);
  theta_.assign(capacity, 0.0f);
  theta_rate_.assign(capacity, 0.0f);
  still_at_.assign(capacity, glm::vec2(0.0f));
  still_jitter2_.assign(capacity, -1.0f);
  jitter_held_.assign(capacity, 0);
  root_heading_.assign(capacity, 0.0f);
  lower_target_.assign(capacity, 0.0f);
  lower_yaw_rate_.assign(capacity, 0.0f);
  rel_dir_.assign(capacity, 0.0f);
  clip_weights_.assign(capacity * nc, 0.0f);
  scratch_target_.assign(capacity * nc, 0.0f);
  idle_time_.assign(capacity, 0.0f);
  cadence_scale_.assign(capacity, 1.0f);
  reach_boost_.assign(capacity, 1.0f);
  tr_index_.assign(capacity, -1);
  tr_stage_.assign(capacity, TransitionStage::kNone);
  for (auto* v :
       {&tr_time_, &tr_weight_, &tr_waited_, &tr_min_cadence_, &tr_chosen_speed_, &tr_lag_,
        &tr_prev_speed_, &tr_prev_phase_, &tr_still_, &tr_moving_, &tr_peak_speed_}) {
    v->assign(capacity, 0.0f);
  }
  tr_rate_.assign(capacity, 1.0f);
  tr_start_due_.assign(capacity, 0);
  tr_counts_.assign(capacity * kNumCounts, 0);
  lod_plan_.assign(capacity, 1);
  lod_dt_s_.assign(capacity, 0.0f);
  lod_elapsed_s_.assign(capacity, 0.0f);
  lod_phase_advance_.assign(capacity, 0.0f);
  lod_tr_advance_.assign(capacity, 0.0f);
  lod_cycles_per_s_.assign(capacity, 0.0f);
  lod_cycles_valid_.assign(capacity, 0);
  lod_root_at_plan_.assign(capacity, glm::vec2(0.0f));
}

void Mediator::set_params(const MediatorParams& p) {
  params_ = p;
  degraded_ = p.mode == MediatorMode::kApm && library_doubtful_;
  if (degraded_) params_.mode = MediatorMode::kNaive;
}

void Mediator::init_slot(int slot, uint32_t id, const glm::vec2& p, const glm::vec2& v,
                         float theta) {
  slot_id_[slot] = id;
  const glm::vec2 vel = finite2(v) && glm::length(v) < kAbsurdSpeed ? v : glm::vec2(0.0f);
  const float th = std::isfinite(theta) ? theta : heading2(vel);
  vel_[slot] = vel;
  vel_rate_[slot] = glm::vec2(0.0f);
  fed_speed_[slot] = glm::length(vel);
  theta_[slot] = th;
  theta_rate_[slot] = 0.0f;
  jitter_held_[slot] = 0;
  const float speed = glm::length(vel);
  const float yaw = speed > params_.stop_speed_m_s ? heading2(vel) : th;
  plans_.lower_yaw[slot] = yaw;
  lower_target_[slot] = yaw;
  lower_yaw_rate_[slot] = 0.0f;
  plans_.root_xz[slot] = usable_position(p) ? p : glm::vec2(0.0f);
  plans_.fresh[slot] = 1;
  // Variety: a random start phase and cadence, from the seed and the id (order-independent).
  std::mt19937_64 rng(params_.seed * 0x9E3779B97F4A7C15ull + id);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  plans_.phase[slot] = u01(rng);
  idle_time_[slot] = 10.0f * u01(rng);
  cadence_scale_[slot] = 1.0f + params_.stride_variation * (2.0f * u01(rng) - 1.0f);
  // Start settled in the clips the current speed asks for (no fade-in from nothing).
  const size_t nc = library_.clips.size();
  choose_clip_weights(library_, params_, speed, 0.0f,
                      std::span<float>(clip_weights_).subspan(slot * nc, nc));
  plans_.blend_progress[slot] = 1.0f;
}

Status Mediator::validate(const AgentFrame& frame, float dt_s) {
  if (!(dt_s > 0.0f) || !std::isfinite(dt_s) || dt_s > 1.0f) {
    return Status::Error("mediator: frame time must be in (0, 1] s, got " + std::to_string(dt_s));
  }
  const size_t n = frame.size();
  if (frame.positions.size() != n || frame.velocities.size() != n || frame.thetas.size() != n) {
    return Status::Error("mediator: frame arrays differ in length: " + std::to_string(n) +
                         " ids, " + std::to_string(frame.positions.size()) + " positions, " +
                         std::to_string(frame.velocities.size()) + " velocities, " +
                         std::to_string(frame.thetas.size()) + " thetas");
  }
  if (n > capacity_) {
    return Status::Error("mediator: " + std::to_string(n) + " agents exceed the capacity of " +
                         std::to_string(capacity_));
  }
  // Ids: none reserved, none twice. Known agents are marked in seen_ (scratch) by slot; newcomers
  // go through a scratch map that is emptied again below. Distinct ids, at most the capacity of
  // them, always find slots once the vanished agents' are freed.
  std::fill(seen_.begin(), seen_.end(), 0);
  Status status = Status::Ok();
  size_t checked = 0;
  for (; checked < n; ++checked) {
    const uint32_t id = frame.ids[checked];
    if (id == 0xffffffffu) {
      status = Status::Error("mediator: agent id 4294967295 is reserved");
      break;
    }
    const int32_t slot = ids_.find(id);
    found_slot_[checked] = slot;
    bool twice = false;
    if (slot >= 0) {
      twice = seen_[slot] != 0;
      seen_[slot] = 1;
    } else {
      bool created = false;
      new_ids_.insert(id, &created);
      twice = !created;
      if (twice) found_slot_[checked] = 0;  // not inserted by this agent: not erased below
    }
    if (twice) {
      status = Status::Error("mediator: agent id " + std::to_string(id) + " appears twice");
      ++checked;
      break;
    }
  }
  for (size_t i = 0; i < checked; ++i) {
    if (found_slot_[i] < 0) new_ids_.erase(frame.ids[i]);
  }
  return status;
}

void Mediator::assign_slots(const AgentFrame& frame) {
  const size_t n = frame.size();
  std::fill(plans_.fresh.begin(), plans_.fresh.end(), 0);
  // Known agents keep their slots; the slots of those that vanished are freed before newcomers
  // take theirs, so a crowd at capacity can swap agents within one frame.
  std::fill(plans_.agent_of_slot.begin(), plans_.agent_of_slot.end(), -1);
  for (size_t s = 0; s < capacity_; ++s) {
    if (!seen_[s] && slot_id_[s] != 0xffffffffu) {
      ids_.erase(slot_id_[s]);
      slot_id_[s] = 0xffffffffu;
    }
  }
  for (size_t i = 0; i < n; ++i) {
    int32_t slot = found_slot_[i];
    if (slot < 0) {
      bool created = false;
      slot = ids_.insert(frame.ids[i], &created);
      assert(slot >= 0 && created);  // validate() made sure
      init_slot(slot, frame.ids[i], frame.positions[i], frame.velocities[i], frame.thetas[i]);
    }
    plans_.slot_of_agent[i] = slot;
    plans_.agent_of_slot[slot] = static_cast<int32_t>(i);
  }
}

Status Mediator::plan(const AgentFrame& frame, float dt_s, FeedbackPolicy policy) {
  // validate: everything is checked before anything is written, so a refused frame leaves the
  // previous plans, feedback and slots as they were (and drawable).
  GK_RETURN_IF_ERROR(validate(frame, dt_s));
  const size_t n = frame.size();
  num_agents_ = n;
  // slots: agent -> slot, newcomers' slots initialised (serial: the id map is shared).
  assign_slots(frame);
  for (size_t i = 0; i < n; ++i) {
    if (!sane_input(frame.positions[i], frame.velocities[i], frame.thetas[i])) ++num_sanitised_;
  }

  // Level of detail: the agents not due this frame are advanced, not planned; a due one is
  // planned over the time since its last plan.
  AnimationPlans& pl = plans_;
  const bool lod = !lod_due_.empty();
  // Plans made without LOD kept no gait frequency for the advance.
  if (lod && !lod_was_on_) std::fill(lod_cycles_valid_.begin(), lod_cycles_valid_.end(), 0);
  lod_was_on_ = lod;
  // Standing through a recording's jitter (filter_pass): a recording's p jitters with its
  // tracker's noise; a simulator's is where its agent is (its jitter is answered with feedback).
  // Once the gate goes off (parameters, mode or source), nothing it learnt or held carries over:
  // held roots are let go (LOD advance_agent reads them) and the state is unknown (-1) until it
  // is next on.
  const bool stand_through_jitter = params_.mode == MediatorMode::kApm &&
                                    params_.stand_through_jitter &&
                                    policy == FeedbackPolicy::kIgnored;
  if (!stand_through_jitter && jitter_gate_was_on_) {
    std::fill(jitter_held_.begin(), jitter_held_.end(), uint8_t{0});
    std::fill(still_jitter2_.begin(), still_jitter2_.end(), -1.0f);
  }
  jitter_gate_was_on_ = stand_through_jitter;
  const float pull = root_pull(dt_s);
  if (lod) {
    // Per agent and its own slot only: in parallel, as the passes.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256),
                      [&](const tbb::blocked_range<size_t>& r) {
                        for (size_t i = r.begin(); i < r.end(); ++i) {
                          const int slot = pl.slot_of_agent[i];
                          lod_plan_[slot] = lod_due_[slot] || pl.fresh[slot];
                          if (lod_plan_[slot]) {
                            lod_dt_s_[slot] = lod_step(slot, dt_s);
                          } else {
                            advance_agent(static_cast<int>(i), slot, frame.positions[i],
                                          frame.velocities[i], frame.thetas[i], dt_s, pull);
                          }
                        }
                      });
  }

  // The whole-crowd passes (mediator/mediator_passes.h), each over every agent due, in order.
  const PassCrowd crowd{library_,
                        params_,
                        dt_s,
                        {pl.slot_of_agent.data(), n},
                        pl.fresh,
                        lod ? std::span<const uint8_t>(lod_plan_) : std::span<const uint8_t>(),
                        lod ? std::span<const float>(lod_dt_s_) : std::span<const float>()};
  const bool honoured = params_.feedback && policy == FeedbackPolicy::kHonoured;
  filter_pass(crowd, frame, pl.root_xz,
              {vel_, vel_rate_, theta_, theta_rate_, still_at_, still_jitter2_, jitter_held_},
              stand_through_jitter, {sim_pos_, sim_vel_, sim_theta_}, pl.speed_m_s, pl.standing);
  root_pass(crowd, sim_pos_, vel_, pl.standing, pl.lower_yaw, pl.root_xz, root_heading_,
            support_hold_allowed_ ? support_reach_ : std::span<const SupportReach>(), honoured,
            root_speed_, hold_, hold_scale_, still_at_, jitter_held_);
  facing_pass(crowd, root_heading_, theta_, pl.standing, lower_target_, pl.lower_yaw,
              lower_yaw_rate_, pl.upper_yaw, rel_dir_, pl.layer_clip, pl.layer_weight);
  weights_pass(crowd, pl.speed_m_s, rel_dir_, tr_min_cadence_, {clip_weights_, scratch_target_},
               pl.layer_clip, pl.layer_weight, pl.blend_progress);
  rate_phase_pass(crowd, pl.layer_clip, pl.layer_weight, pl.speed_m_s, cadence_scale_, pl.lower_yaw,
                  tr_weight_, {support_reach_, pl.root_xz, vel_, reach_boost_}, pl.phase,
                  idle_time_, pl.playback_rate, pl.gait_weight, pl.travel_yaw);
  transition_pass(crowd, pl.speed_m_s, pl.playback_rate, pl.standing, pl.layer_clip,
                  pl.layer_weight, pl.gait_weight, pl.phase,
                  {tr_index_, tr_stage_, tr_time_, tr_weight_, tr_rate_, tr_waited_,
                   tr_min_cadence_, tr_chosen_speed_, tr_lag_, tr_prev_speed_, tr_prev_phase_,
                   tr_still_, tr_moving_, tr_peak_speed_, tr_start_due_, tr_counts_, reach_boost_});
  contacts_pass(crowd, pl.layer_clip, pl.layer_weight, pl.phase, idle_time_, tr_time_,
                pl.gait_weight, pl.playback_rate, tr_rate_, pl.layer_time_s,
                {{pl.plant[0], pl.plant[1]},
                 {pl.hold[0], pl.hold[1]},
                 {pl.swing_progress[0], pl.swing_progress[1]},
                 {pl.landing_s[0], pl.landing_s[1]},
                 {pl.gait_toe_y[0], pl.gait_toe_y[1]},
                 {pl.stand_toe_y[0], pl.stand_toe_y[1]},
                 {pl.clip_toe_speed[0], pl.clip_toe_speed[1]},
                 pl.double_support,
                 pl.standing_votes});
  feedback_pass(
      crowd, honoured, sim_pos_, sim_vel_, sim_theta_, fed_speed_, pl.lower_yaw, pl.standing,
      pl.gait_weight, hold_, hold_scale_,
      {feedback_.has_feedback, feedback_.positions, feedback_.velocities, feedback_.thetas});
  if (lod) {
    for (size_t i = 0; i < n; ++i) {
      const int slot = pl.slot_of_agent[i];
      if (!lod_plan_[slot]) continue;
      lod_root_at_plan_[slot] = pl.root_xz[slot];
      lod_elapsed_s_[slot] = lod_phase_advance_[slot] = lod_tr_advance_[slot] = 0.0f;
      const GaitFrequency gf = gait_frequency(library_, &pl.layer_clip[slot * kMaxBlendLayers],
                                              &pl.layer_weight[slot * kMaxBlendLayers]);
      lod_cycles_per_s_[slot] = gf.gait_weight > 0.0f ? gf.cycles_per_s : 0.0f;
      lod_cycles_valid_[slot] = 1;
    }
  }
  return Status::Ok();
}

// LOD: the agent's phase, clip times, idle clock and transition clock advance with the rates of
// its last plan, and its root follows p as the root pass's would (pulled_root). Clips, weights,
// facing and springs wait for its next plan.
void Mediator::advance_agent(int agent, int slot, const glm::vec2& p_in, const glm::vec2& v_in,
                             float theta_in, float dt, float pull) {
  AnimationPlans& pl = plans_;
  const glm::vec2 p = usable_position(p_in) ? p_in : pl.root_xz[slot];
  glm::vec2 v = finite2(v_in) ? v_in : vel_[slot];
  if (glm::length(v) > kAbsurdSpeed) v = vel_[slot];
  sim_pos_[agent] = p;
  sim_vel_[agent] = v;
  sim_theta_[agent] = std::isfinite(theta_in) ? theta_in : theta_[slot];
  feedback_.has_feedback[agent] = 0;
  fed_speed_[slot] = glm::length(v);
  feedback_.positions[agent] = p;
  feedback_.velocities[agent] = v;
  feedback_.thetas[agent] = std::isfinite(theta_in) ? theta_in : theta_[slot];
  // As the root pass draws it: an agent held standing through its jitter where it stands.
  if (params_.mode != MediatorMode::kApm) {
    pl.root_xz[slot] = p;
  } else if (jitter_held_[slot]) {
    pl.root_xz[slot] = held_root(pl.root_xz[slot], still_at_[slot], p, dt, pull);
  } else {
    pl.root_xz[slot] = pulled_root(pl.root_xz[slot], vel_[slot], p, dt, pull);
  }
  // The gait frequency of the planned blend, as the rate and phase pass takes it (kept from the
  // agent's last plan: its layers and weights have not changed since).
  const int16_t* lc = &pl.layer_clip[slot * kMaxBlendLayers];
  const float* lw = &pl.layer_weight[slot * kMaxBlendLayers];
  float* lt = &pl.layer_time_s[slot * kMaxBlendLayers];
  if (!lod_cycles_valid_[slot]) {
    const GaitFrequency gf = gait_frequency(library_, lc, lw);
    lod_cycles_per_s_[slot] = gf.gait_weight > 0.0f ? gf.cycles_per_s : 0.0f;
    lod_cycles_valid_[slot] = 1;
  }
  if (lod_cycles_per_s_[slot] > 0.0f) {
    const float step = lod_cycles_per_s_[slot] * pl.playback_rate[slot] * dt;
    pl.phase[slot] = near_fmod(pl.phase[slot] + step, 1.0f);
    lod_phase_advance_[slot] += step;
  }
  idle_time_[slot] += dt;
  lod_elapsed_s_[slot] += dt;
  // A transition's clock, at its last rate.
  const TransitionStage stage = tr_stage_[slot];
  if (stage == TransitionStage::kPlaying || stage == TransitionStage::kLeaving) {
    const float before = tr_time_[slot];
    const float end = library_.transitions[tr_index_[slot]].duration_s;
    tr_time_[slot] = std::min(before + tr_rate_[slot] * dt, end);
    lod_tr_advance_[slot] += tr_time_[slot] - before;
    // The gait phase follows the transition's own steps, as the transition pass has it.
    pl.phase[slot] = library_.transitions[tr_index_[slot]].phase_at(tr_time_[slot]);
  }
  // Only the layers pose synthesis samples (weight > 0), as the contacts pass.
  for (int k = 0; k < kMaxBlendLayers; ++k) {
    if (lw[k] <= 0.0f) continue;
    lt[k] = layer_time(library_.clips[lc[k]], pl.phase[slot], idle_time_[slot], tr_time_[slot]);
  }
}

std::array<uint64_t, kNumCounts> Mediator::transition_counts() const {
  std::array<uint64_t, kNumCounts> sum{};
  for (size_t slot = 0; slot < capacity_; ++slot) {
    for (int k = 0; k < kNumCounts; ++k) sum[k] += tr_counts_[slot * kNumCounts + k];
  }
  return sum;
}

// LOD: the step [s] a due agent is planned over: the time since its last plan. The phase, idle
// clock and root are taken back to where that plan left them, so that the passes advance them
// once over the whole step (its root filter predicts from the last plan's root).
float Mediator::lod_step(int slot, float dt) {
  if (plans_.fresh[slot] || lod_elapsed_s_[slot] <= 0.0f) return dt;
  const float elapsed = lod_elapsed_s_[slot] + dt;
  float& phase = plans_.phase[slot];
  phase -= std::fmod(lod_phase_advance_[slot], 1.0f);
  if (phase < 0.0f) phase += 1.0f;
  idle_time_[slot] -= lod_elapsed_s_[slot];
  tr_time_[slot] -= lod_tr_advance_[slot];
  plans_.root_xz[slot] = lod_root_at_plan_[slot];
  return std::min(elapsed, 1.0f);
}

}  // namespace gk
