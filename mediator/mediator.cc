#include "mediator/mediator.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>
#include <random>

#include <tbb/parallel_for.h>

#include "mediator/springs.h"

namespace gk {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kAbsurdSpeed = 15.0f;    // [m/s] faster simulator velocities are treated as errors
constexpr float kRootPullTime = 0.25f;   // [s] how fast the rendered root is pulled onto p
constexpr float kMaxRootOffset = 0.06f;  // [m] the rendered root never strays further from p
constexpr float kSwitchHysteresis =
    0.26f;  // [rad] a new travel direction group must be this much better

bool finite2(const glm::vec2& v) { return std::isfinite(v.x) && std::isfinite(v.y); }
// [m] Positions further out than this from the origin are a simulator's garbage (1e30), not a
// place; a float there cannot even hold a footstep.
constexpr float kMaxCoordinate = 1e6f;
bool usable_position(const glm::vec2& p) {
  return finite2(p) && std::abs(p.x) <= kMaxCoordinate && std::abs(p.y) <= kMaxCoordinate;
}
float heading2(const glm::vec2& v) { return std::atan2(v.x, v.y); }

// Speed bracket within one direction group, with the standing clip at speed 0 below it.
void add_group_weights(const LocomotionLibrary& lib, const DirectionGroup& g, float speed,
                       float share, float* w) {
  if (share <= 0.0f) return;
  const std::vector<int>& c = g.clips;
  const float first = lib.clips[c.front()].speed_m_s;
  if (speed <= first) {
    const float u = std::clamp(speed / first, 0.0f, 1.0f);
    w[lib.idle] += share * (1.0f - u);
    w[c.front()] += share * u;
    return;
  }
  for (size_t k = 0; k + 1 < c.size(); ++k) {
    const float a = lib.clips[c[k]].speed_m_s, b = lib.clips[c[k + 1]].speed_m_s;
    if (speed <= b) {
      const float u = (speed - a) / std::max(b - a, 1e-6f);
      w[c[k]] += share * (1.0f - u);
      w[c[k + 1]] += share * u;
      return;
    }
  }
  w[c.back()] += share;
}

}  // namespace

Mediator::Mediator(const LocomotionLibrary& library, const MediatorParams& params, size_t capacity)
    : library_(library), params_(params), capacity_(capacity), ids_(capacity) {
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
  plans_.lower_yaw.assign(capacity, 0.0f);
  plans_.upper_yaw.assign(capacity, 0.0f);
  plans_.travel_yaw.assign(capacity, 0.0f);
  plans_.playback_rate.assign(capacity, 1.0f);
  plans_.speed_m_s.assign(capacity, 0.0f);
  for (int s = 0; s < 2; ++s) {
    plans_.plant[s].assign(capacity, 1.0f);
    plans_.hold[s].assign(capacity, 1.0f);
    plans_.gait_toe_y[s].assign(capacity, 0.0f);
    plans_.swing_progress[s].assign(capacity, 0.0f);
    plans_.double_support.assign(capacity, 0.0f);
  }
  plans_.phase.assign(capacity, 0.0f);
  plans_.blend_progress.assign(capacity, 1.0f);
  plans_.standing.assign(capacity, 1);
  plans_.fresh.assign(capacity, 1);
  feedback_.has_feedback.assign(capacity, 0);
  feedback_.positions.assign(capacity, glm::vec2(0.0f));
  feedback_.velocities.assign(capacity, glm::vec2(0.0f));
  feedback_.thetas.assign(capacity, 0.0f);
  sim_vel_.assign(capacity, glm::vec2(0.0f));
  vel_.assign(capacity, glm::vec2(0.0f));
  vel_rate_.assign(capacity, glm::vec2(0.0f));
  theta_.assign(capacity, 0.0f);
  theta_rate_.assign(capacity, 0.0f);
  lower_target_.assign(capacity, 0.0f);
  clip_weights_.assign(capacity * nc, 0.0f);
  scratch_target_.assign(capacity * nc, 0.0f);
  phase_.assign(capacity, 0.0f);
  idle_time_.assign(capacity, 0.0f);
  cadence_scale_.assign(capacity, 1.0f);
  fade_.assign(capacity, 1.0f);
  dominant_.assign(capacity, static_cast<int16_t>(library.idle));
  lod_elapsed_s_.assign(capacity, 0.0f);
  lod_phase_advance_.assign(capacity, 0.0f);
  lod_root_at_plan_.assign(capacity, glm::vec2(0.0f));
}

void Mediator::init_slot(int slot, uint32_t id, const glm::vec2& p, const glm::vec2& v,
                         float theta) {
  slot_id_[slot] = id;
  const glm::vec2 vel = finite2(v) && glm::length(v) < kAbsurdSpeed ? v : glm::vec2(0.0f);
  const float th = std::isfinite(theta) ? theta : heading2(vel);
  vel_[slot] = vel;
  vel_rate_[slot] = glm::vec2(0.0f);
  theta_[slot] = th;
  theta_rate_[slot] = 0.0f;
  const float speed = glm::length(vel);
  const float yaw = speed > params_.stop_speed_m_s ? heading2(vel) : th;
  plans_.lower_yaw[slot] = yaw;
  lower_target_[slot] = yaw;
  plans_.root_xz[slot] = usable_position(p) ? p : glm::vec2(0.0f);
  plans_.fresh[slot] = 1;
  // Variety: a random start phase and cadence, from the seed and the id (order-independent).
  std::mt19937_64 rng(params_.seed * 0x9E3779B97F4A7C15ull + id);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  phase_[slot] = u01(rng);
  idle_time_[slot] = 10.0f * u01(rng);
  cadence_scale_[slot] = 1.0f + params_.stride_variation * (2.0f * u01(rng) - 1.0f);
  // Start settled in the clips the current speed asks for (no fade-in from nothing).
  const size_t nc = library_.clips.size();
  float* w = &clip_weights_[slot * nc];
  std::fill(w, w + nc, 0.0f);
  choose_weights(slot, speed, 0.0f, w);
  fade_[slot] = 1.0f;
}

void Mediator::choose_weights(int slot, float speed, float rel_dir, float* w) const {
  const LocomotionLibrary& lib = library_;
  const size_t nc = lib.clips.size();
  std::fill(w, w + nc, 0.0f);
  if (speed < params_.stop_speed_m_s) {
    w[lib.idle] = 1.0f;
    return;
  }
  if (params_.mode != MediatorMode::kApm) {
    // Nearest-speed forward clip (or standing), no blending.
    const DirectionGroup& g = lib.groups[lib.forward_group];
    int best = lib.idle;
    float best_d = speed;
    for (int c : g.clips) {
      const float d = std::abs(lib.clips[c].speed_m_s - speed);
      if (d < best_d) {
        best_d = d;
        best = c;
      }
    }
    w[best] = 1.0f;
    return;
  }
  (void)slot;
  const std::vector<DirectionGroup>& groups = lib.groups;
  if (groups.size() == 1) {
    add_group_weights(lib, groups[0], speed, 1.0f, w);
    return;
  }
  // The two groups whose directions bracket rel_dir (circularly), interpolated by angle.
  const int n = static_cast<int>(groups.size());
  int lo = n - 1;
  for (int g = 0; g < n; ++g) {
    if (groups[g].direction_rad <= rel_dir) lo = g;
  }
  if (rel_dir < groups[0].direction_rad) lo = n - 1;
  const int hi = (lo + 1) % n;
  const float a = groups[lo].direction_rad;
  float span = wrap_pi(groups[hi].direction_rad - a);
  if (span <= 0.0f) span += 2.0f * kPi;
  float off = wrap_pi(rel_dir - a);
  if (off < 0.0f) off += 2.0f * kPi;
  const float u = std::clamp(off / span, 0.0f, 1.0f);
  add_group_weights(lib, groups[lo], speed, 1.0f - u, w);
  add_group_weights(lib, groups[hi], speed, u, w);
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

Status Mediator::plan(const AgentFrame& frame, float dt_s, FeedbackPolicy policy) {
  // Everything is checked before anything is written: a refused frame leaves the previous plans,
  // feedback and slots as they were (and drawable).
  GK_RETURN_IF_ERROR(validate(frame, dt_s));
  const size_t n = frame.size();
  num_agents_ = n;
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

  const bool feedback = params_.feedback && policy == FeedbackPolicy::kHonoured;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 64), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const int slot = plans_.slot_of_agent[i];
      if (!lod_due_.empty() && !lod_due_[slot] && !plans_.fresh[slot]) {
        advance_agent(static_cast<int>(i), slot, frame.positions[i], frame.velocities[i],
                      frame.thetas[i], dt_s);
        continue;
      }
      plan_agent(static_cast<int>(i), slot, frame.positions[i], frame.velocities[i],
                 frame.thetas[i], lod_due_.empty() ? dt_s : lod_step(slot, dt_s), feedback);
      lod_root_at_plan_[slot] = plans_.root_xz[slot];
      lod_elapsed_s_[slot] = lod_phase_advance_[slot] = 0.0f;
    }
  });
  for (size_t i = 0; i < n; ++i) {
    const glm::vec2 v = frame.velocities[i];
    if (!finite2(v) || glm::length(v) > kAbsurdSpeed || !usable_position(frame.positions[i]) ||
        !std::isfinite(frame.thetas[i])) {
      ++num_sanitised_;
    }
  }
  return Status::Ok();
}

void Mediator::plan_agent(int agent, int slot, const glm::vec2& p_in, const glm::vec2& v_in,
                          float theta_in, float dt, bool feedback) {
  const LocomotionLibrary& lib = library_;
  const MediatorParams& P = params_;
  const size_t nc = lib.clips.size();
  AnimationPlans& pl = plans_;

  // Sanitise what the simulator gave (NaN, absurd speeds): hold the last good values.
  const glm::vec2 p = usable_position(p_in) ? p_in : pl.root_xz[slot];
  glm::vec2 v = finite2(v_in) ? v_in : vel_[slot];
  if (glm::length(v) > kAbsurdSpeed) v = vel_[slot];
  const float theta_raw = std::isfinite(theta_in) ? theta_in : theta_[slot];
  sim_vel_[agent] = v;

  const bool apm = P.mode == MediatorMode::kApm;
  // 1. Filtering (APM only: the naive and rate modes take the simulator as it is).
  if (apm) {
    critical_spring(vel_[slot], vel_rate_[slot], v, P.velocity_halflife_s, dt);
    const float goal = theta_[slot] + wrap_pi(theta_raw - theta_[slot]);
    critical_spring(theta_[slot], theta_rate_[slot], goal, P.theta_halflife_s, dt);
  } else {
    vel_[slot] = v;
    theta_[slot] = theta_raw;
  }
  const glm::vec2 vel = vel_[slot];
  const float speed = glm::length(vel);
  const float theta = wrap_pi(theta_[slot]);
  const bool standing = speed < P.stop_speed_m_s;
  // 8. The root follows p: predicted with the filtered velocity and pulled onto p, so a simulator's
  // frame-to-frame jitter (velocity flips in a jam) does not shake the body, while a steady walk
  // is tracked without lag. Never more than kMaxRootOffset from p. The legs then walk where the
  // drawn root really goes.
  glm::vec2 root_vel = vel;
  if (apm && !pl.fresh[slot]) {
    const glm::vec2 predicted = pl.root_xz[slot] + vel * dt;
    glm::vec2 root = predicted + (p - predicted) * (1.0f - std::exp(-dt / kRootPullTime));
    const glm::vec2 off = root - p;
    const float len = glm::length(off);
    if (len > kMaxRootOffset) root = p + off * (kMaxRootOffset / len);
    root_vel = (root - pl.root_xz[slot]) / dt;
    pl.root_xz[slot] = root;
  } else {
    pl.root_xz[slot] = p;
  }
  const float travel =
      standing ? pl.lower_yaw[slot] : heading2(glm::length(root_vel) > 1e-3f ? root_vel : vel);

  // 2./3. Lower body follows v (or a strafe/backward orientation), upper body faces theta.
  float psi = pl.lower_yaw[slot];
  if (!apm) {
    psi = standing ? psi : travel;
  } else {
    float target = travel;
    if (standing) {
      target = theta;
    } else if (lib.has_direction_clips()) {
      // Pick the travel-direction group that leaves the upper body the least twist.
      const float current_d = wrap_pi(travel - lower_target_[slot]);
      float best_cost = 1e9f, best_d = 0.0f;
      for (const DirectionGroup& g : lib.groups) {
        float cost = std::abs(wrap_pi(theta - (travel - g.direction_rad)));
        if (std::abs(wrap_pi(g.direction_rad - current_d)) < 0.2f) cost -= kSwitchHysteresis;
        if (cost < best_cost) {
          best_cost = cost;
          best_d = g.direction_rad;
        }
      }
      target = travel - best_d;
    }
    lower_target_[slot] = target;
    const float rate = glm::radians(P.lower_turn_rate_deg_s) * (standing ? 0.5f : 1.0f);
    psi = wrap_pi(approach_angle(psi, target, rate * dt));
  }
  const float rel_dir = standing || !apm ? 0.0f : wrap_pi(travel - psi);

  // 4./6. Target blend weights, faded toward over the blend time (APM) or switched at once.
  float* w = &clip_weights_[slot * nc];
  float* target_w = &scratch_target_[slot * nc];
  choose_weights(slot, speed, rel_dir, target_w);
  if (apm && !pl.fresh[slot]) {
    const float step = dt / P.blend_time_s;
    float diff = 0.0f;
    for (size_t c = 0; c < nc; ++c) {
      const float d = target_w[c] - w[c];
      w[c] += std::clamp(d, -step, step);
      diff += std::abs(target_w[c] - w[c]);
    }
    fade_[slot] = 1.0f - 0.5f * diff;
  } else {
    std::copy(target_w, target_w + nc, w);
    fade_[slot] = 1.0f;
  }
  // Keep the kMaxBlendLayers heaviest clips.
  int16_t* lc = &pl.layer_clip[slot * kMaxBlendLayers];
  float* lw = &pl.layer_weight[slot * kMaxBlendLayers];
  float* lt = &pl.layer_time_s[slot * kMaxBlendLayers];
  std::fill(lw, lw + kMaxBlendLayers, 0.0f);
  for (size_t c = 0; c < nc; ++c) {
    if (w[c] <= 1e-4f) continue;
    int k_min = 0;
    for (int k = 1; k < kMaxBlendLayers; ++k) {
      if (lw[k] < lw[k_min]) k_min = k;
    }
    if (w[c] > lw[k_min]) {
      lw[k_min] = w[c];
      lc[k_min] = static_cast<int16_t>(c);
    }
  }
  float total = 0.0f;
  for (int k = 0; k < kMaxBlendLayers; ++k) total += lw[k];
  if (total <= 0.0f) {
    lw[0] = 1.0f;
    lc[0] = static_cast<int16_t>(lib.idle);
    total = 1.0f;
  }
  // 5. Playback rate from speed, within limits; the rest is stride warping (foot IK), beyond that
  // the deliverable speed goes back to the simulator.
  float native = 0.0f, freq = 0.0f, gait_w = 0.0f;
  glm::vec2 dir_sum(0.0f);
  for (int k = 0; k < kMaxBlendLayers; ++k) {
    lw[k] /= total;
    const LocomotionClip& clip = lib.clips[lc[k]];
    native += lw[k] * clip.speed_m_s;
    if (clip.gait && lw[k] > 0.0f) {
      freq += lw[k] / clip.cycle_s;
      gait_w += lw[k];
      dir_sum += lw[k] * glm::vec2(std::sin(clip.direction_rad), std::cos(clip.direction_rad));
    }
  }
  float rate = 1.0f;
  if (gait_w > 0.0f) {
    freq /= gait_w;
    if (P.mode == MediatorMode::kNaive) {
      rate = 1.0f;
    } else if (native > 1e-3f) {
      rate = std::clamp(speed / native * cadence_scale_[slot], P.min_playback_rate,
                        P.max_playback_rate);
    }
    phase_[slot] = std::fmod(phase_[slot] + freq * rate * dt, 1.0f);
  }
  idle_time_[slot] += dt;
  // Clip times at the shared gait phase (phase-synchronised blending; a new clip starts in phase).
  // Foot flags are voted by the gait clips alone once they carry a quarter of the blend: a standing
  // clip's "both feet down" would otherwise keep a stepping foot locked while it swings.
  float plant[2] = {0.0f, 0.0f}, hold[2] = {0.0f, 0.0f}, vote_w = 0.0f;
  float toe_gait[2] = {0.0f, 0.0f}, swing[2] = {0.0f, 0.0f}, walk = 0.0f;
  const bool gait_votes = gait_w >= 0.25f;
  for (int k = 0; k < kMaxBlendLayers; ++k) {
    const LocomotionClip& clip = lib.clips[lc[k]];
    lt[k] = clip.gait ? clip.time_at_phase(phase_[slot])
                      : std::fmod(idle_time_[slot], std::max(clip.clip.duration_s(), 1e-3f));
    if (lw[k] <= 0.0f) continue;
    const int nf = clip.clip.num_frames;
    auto wrap = [&](int i) {
      return clip.clip.loops ? ((i % nf) + nf) % nf : std::clamp(i, 0, nf - 1);
    };
    const float ft = lt[k] * clip.clip.fps;
    const int f = wrap(static_cast<int>(std::lround(ft)));
    // Toe heights between frames (a 24 or 30 fps clip must not step the foot every other frame).
    const int f0 = static_cast<int>(std::floor(ft));
    const float fu = ft - static_cast<float>(f0);
    for (int s = 0; s < 2; ++s) {
      if (clip.gait && !clip.toe_height_m[s].empty()) {
        const auto& h = clip.toe_height_m[s];
        const float hv = h[wrap(f0)] + fu * (h[wrap(f0 + 1)] - h[wrap(f0)]);
        toe_gait[s] += lw[k] * (hv + clip.toe_floor_m[s]);
      }
    }
    if (gait_votes && !clip.gait) continue;
    vote_w += lw[k];
    if (clip.double_support) walk += lw[k];
    for (int s = 0; s < 2; ++s) {
      plant[s] += lw[k] * clip.plant[s][f];
      if (!clip.swing_progress[s].empty()) swing[s] += lw[k] * clip.swing_progress[s][f];
      hold[s] += lw[k] * clip.hold[s][f];
    }
  }
  for (int s = 0; s < 2; ++s) {
    plant[s] /= std::max(vote_w, 1e-6f);
    hold[s] /= std::max(vote_w, 1e-6f);
  }
  // 8. Feedback: the speed and torso orientation the animation can deliver.
  const int a = agent;
  feedback_.has_feedback[a] = 0;
  feedback_.positions[a] = p;
  feedback_.velocities[a] = v;
  feedback_.thetas[a] = theta_raw;
  if (apm && feedback) {
    const DirectionGroup& fg = lib.groups[lib.forward_group];
    const float max_speed =
        lib.clips[fg.clips.back()].speed_m_s * P.max_playback_rate * (1.0f + P.max_stride_warp);
    const float v_len = glm::length(v);
    if (v_len > max_speed) {
      feedback_.velocities[a] = v * (max_speed / v_len);
      feedback_.has_feedback[a] = 1;
    }
    // With forward clips only, the legs walk where the lower body faces, and it turns at a
    // limited rate: a velocity that turns faster is turned back to within turn_feedback_deg of
    // that facing, so the simulator moves the agent where its feet go (a jam's sideways jitter
    // would otherwise look like skating). A library with strafe or backward clips takes sideways
    // velocities by blending directions instead (and its facing may be mid-switch between
    // direction groups, which is no direction to hold the simulator to).
    const glm::vec2 v_out = feedback_.velocities[a];
    const float v_out_len = glm::length(v_out);
    const float off = wrap_pi(heading2(v_out) - psi);
    const float slack = glm::radians(P.turn_feedback_deg);
    if (!lib.has_direction_clips() && !standing && gait_w > 0.0f && v_out_len > P.stop_speed_m_s &&
        std::abs(off) > slack) {
      const float dir = psi + std::clamp(off, -slack, slack);
      feedback_.velocities[a] = v_out_len * glm::vec2(std::sin(dir), std::cos(dir));
      feedback_.has_feedback[a] = 1;
    }
    const float twist = wrap_pi(theta_raw - psi);
    const float limit = glm::radians(P.torsion_limit_deg);
    if (std::abs(twist) > limit && !lib.has_direction_clips()) {
      feedback_.thetas[a] = wrap_pi(psi + std::clamp(twist, -limit, limit));
      feedback_.has_feedback[a] = 1;
    }
  }

  pl.lower_yaw[slot] = psi;
  pl.upper_yaw[slot] = apm ? theta : psi;
  pl.travel_yaw[slot] = wrap_pi(psi + (gait_w > 0.0f ? std::atan2(dir_sum.x, dir_sum.y) : 0.0f));
  pl.playback_rate[slot] = gait_w > 0.0f ? rate : 1.0f;
  pl.speed_m_s[slot] = speed;
  pl.gait_weight[slot] = gait_w;
  for (int s = 0; s < 2; ++s) {
    pl.plant[s][slot] = plant[s];
    pl.hold[s][slot] = hold[s];
    pl.swing_progress[s][slot] = swing[s] / std::max(vote_w, 1e-6f);
    pl.gait_toe_y[s][slot] = gait_w > 0.0f ? toe_gait[s] / gait_w : 0.0f;
  }
  pl.double_support[slot] = walk / std::max(vote_w, 1e-6f);
  pl.phase[slot] = phase_[slot];
  pl.blend_progress[slot] = fade_[slot];
  pl.standing[slot] = standing;
}

// LOD: the agent's phase, clip times and idle clock advance with the rate of its last plan, and
// its root follows p as plan_agent's would (predicted with the filtered velocity, pulled onto p,
// never more than kMaxRootOffset away). Clips, weights, facing and springs wait for its next plan.
void Mediator::advance_agent(int agent, int slot, const glm::vec2& p_in, const glm::vec2& v_in,
                             float theta_in, float dt) {
  AnimationPlans& pl = plans_;
  const glm::vec2 p = usable_position(p_in) ? p_in : pl.root_xz[slot];
  glm::vec2 v = finite2(v_in) ? v_in : vel_[slot];
  if (glm::length(v) > kAbsurdSpeed) v = vel_[slot];
  sim_vel_[agent] = v;
  feedback_.has_feedback[agent] = 0;
  feedback_.positions[agent] = p;
  feedback_.velocities[agent] = v;
  feedback_.thetas[agent] = std::isfinite(theta_in) ? theta_in : theta_[slot];
  if (params_.mode == MediatorMode::kApm) {
    const glm::vec2 predicted = pl.root_xz[slot] + vel_[slot] * dt;
    glm::vec2 root = predicted + (p - predicted) * (1.0f - std::exp(-dt / kRootPullTime));
    const glm::vec2 off = root - p;
    const float len = glm::length(off);
    if (len > kMaxRootOffset) root = p + off * (kMaxRootOffset / len);
    pl.root_xz[slot] = root;
  } else {
    pl.root_xz[slot] = p;
  }
  // The gait frequency of the planned blend, as plan_agent computes it.
  const int16_t* lc = &pl.layer_clip[slot * kMaxBlendLayers];
  const float* lw = &pl.layer_weight[slot * kMaxBlendLayers];
  float* lt = &pl.layer_time_s[slot * kMaxBlendLayers];
  float freq = 0.0f, gait_w = 0.0f;
  for (int k = 0; k < kMaxBlendLayers; ++k) {
    const LocomotionClip& clip = library_.clips[lc[k]];
    if (clip.gait && lw[k] > 0.0f) {
      freq += lw[k] / clip.cycle_s;
      gait_w += lw[k];
    }
  }
  if (gait_w > 0.0f) {
    const float step = freq / gait_w * pl.playback_rate[slot] * dt;
    phase_[slot] = std::fmod(phase_[slot] + step, 1.0f);
    lod_phase_advance_[slot] += step;
  }
  idle_time_[slot] += dt;
  lod_elapsed_s_[slot] += dt;
  for (int k = 0; k < kMaxBlendLayers; ++k) {
    const LocomotionClip& clip = library_.clips[lc[k]];
    lt[k] = clip.gait ? clip.time_at_phase(phase_[slot])
                      : std::fmod(idle_time_[slot], std::max(clip.clip.duration_s(), 1e-3f));
  }
  pl.phase[slot] = phase_[slot];
}

// LOD: the step [s] a due agent is planned over: the time since its last plan. The phase, idle
// clock and root are taken back to where that plan left them, so that plan_agent advances them
// once over the whole step (its root filter predicts from the last plan's root).
float Mediator::lod_step(int slot, float dt) {
  if (plans_.fresh[slot] || lod_elapsed_s_[slot] <= 0.0f) return dt;
  const float elapsed = lod_elapsed_s_[slot] + dt;
  phase_[slot] -= std::fmod(lod_phase_advance_[slot], 1.0f);
  if (phase_[slot] < 0.0f) phase_[slot] += 1.0f;
  idle_time_[slot] -= lod_elapsed_s_[slot];
  plans_.root_xz[slot] = lod_root_at_plan_[slot];
  return std::min(elapsed, 1.0f);
}

}  // namespace gk
