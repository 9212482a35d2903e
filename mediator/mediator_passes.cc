#include "mediator/mediator_passes.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <tbb/parallel_for.h>

#include "animation/near_fmod.h"
#include "mediator/animation_plans.h"
#include "mediator/springs.h"

namespace gk {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kSwitchHysteresis =
    0.26f;  // [rad] a new travel direction group must be this much better

bool is_apm(const PassCrowd& c) { return c.params.mode == MediatorMode::kApm; }

// Runs fn(agent, slot) for every agent of the frame that is planned this frame (all of them
// without a level of detail), in parallel (blocks of 64 agents).
template <typename Fn>
void for_each_agent(const PassCrowd& c, Fn&& fn) {
  const std::span<const int32_t> slots = c.slot_of_agent;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, slots.size(), 64),
                    [&](const tbb::blocked_range<size_t>& r) {
                      for (size_t i = r.begin(); i < r.end(); ++i) {
                        if (c.plans(slots[i])) fn(i, slots[i]);
                      }
                    });
}

// Speed bracket within one direction group, with the standing clip at speed 0 below it.
//
// Below the slowest clip a person both shortens the step and slows the cadence, keeping the walk
// ratio (step length over cadence) about constant (GAIT.md): at a share x of the slowest clip's
// speed, cadence and step length are both about sqrt(x) of its own. The blend with the standing
// clip shortens the stride by the gait clip's weight u, and the playback rate (speed over the
// blend's native speed, x / u) sets the cadence: u = sqrt(x) gives both sqrt(x), down to the
// slowest cadence allowed (min_rate), below which the cadence stays there and the stride shortens
// alone. (Weighting by x alone kept the slowest clip's cadence at any speed and folded all of the
// slowing into the standing blend, which also flattens the swing.)
void add_group_weights(const LocomotionLibrary& lib, const DirectionGroup& g, float speed,
                       float share, float min_rate, float max_rate, std::span<float> w) {
  if (share <= 0.0f) return;
  const std::vector<int>& c = g.clips;
  const float first = lib.clips[c.front()].speed_m_s;
  if (speed <= first) {
    const float x = std::clamp(speed / first, 0.0f, 1.0f);
    const float u = std::min(std::sqrt(x), x / std::max(min_rate, 1e-3f));
    w[lib.idle] += share * (1.0f - u);
    w[c.front()] += share * u;
    return;
  }
  for (size_t k = 0; k + 1 < c.size(); ++k) {
    const float a = lib.clips[c[k]].speed_m_s, b = lib.clips[c[k + 1]].speed_m_s;
    if (speed <= b) {
      const bool walk_to_run =
          lib.clips[c[k]].double_support && !lib.clips[c[k + 1]].double_support;
      // A person walks or runs, never both at once (GAIT.md): where the walk played faster and
      // the run played slower both reach the walk-run transition speed, each plays alone on its
      // side of it (the playback rate matches the speed), and the gait changes over a band of
      // a tenth of that speed about it (within what both can play). A blend of the two would
      // mix the walk's double support with the run's flight: feet that land at the walk's
      // contact while the run's are still swinging forward, stopped dead or sliding.
      const float walk_top = a * max_rate, run_bottom = b * min_rate;
      if (walk_to_run && run_bottom < walk_top) {
        const float centre = std::clamp(lib.walk_run_speed_m_s, run_bottom, walk_top);
        const float half = 0.05f * centre;
        const float lo = std::max(run_bottom, centre - half);
        const float hi = std::min(walk_top, centre + half);
        const float u = std::clamp((speed - lo) / std::max(hi - lo, 1e-6f), 0.0f, 1.0f);
        w[c[k]] += share * (1.0f - u);
        w[c[k + 1]] += share * u;
        return;
      }
      // Between a walk and a run the heavier clip's feet lead (its contacts win the vote, its
      // swing dominates): the run, with its flight phase, never outweighs the walk below the
      // walk-run transition speed. Where the clips' midpoint is below it, the run's weight
      // reaches one half there, not at the midpoint (a slow walk and a bouncy jog would
      // otherwise have a 1.9 m/s pedestrian float between strides).
      float even = 0.5f * (a + b);  // speed at which the two weigh the same
      if (walk_to_run) {
        // No further than halfway from the midpoint to the run: the run's weight still rises
        // over a quarter of the bracket (a run clip slower than the transition speed would
        // otherwise take all the weight in a step at its own speed).
        even = std::clamp(lib.walk_run_speed_m_s, even, 0.5f * (even + b));
      }
      const float u = speed <= even ? 0.5f * (speed - a) / std::max(even - a, 1e-6f)
                                    : 0.5f + 0.5f * (speed - even) / std::max(b - even, 1e-6f);
      w[c[k]] += share * (1.0f - u);
      w[c[k + 1]] += share * u;
      return;
    }
  }
  w[c.back()] += share;
}

}  // namespace

void choose_clip_weights(const LocomotionLibrary& lib, const MediatorParams& params, float speed,
                         float rel_dir, std::span<float> w, float min_cadence) {
  const float min_rate = std::max(params.min_playback_rate, min_cadence);
  const float max_rate = params.max_playback_rate;
  std::fill(w.begin(), w.end(), 0.0f);
  if (speed < params.stop_speed_m_s) {
    w[lib.idle] = 1.0f;
    return;
  }
  if (params.mode != MediatorMode::kApm) {
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
  const std::vector<DirectionGroup>& groups = lib.groups;
  if (groups.size() == 1) {
    add_group_weights(lib, groups[0], speed, 1.0f, min_rate, max_rate, w);
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
  add_group_weights(lib, groups[lo], speed, 1.0f - u, min_rate, max_rate, w);
  add_group_weights(lib, groups[hi], speed, u, min_rate, max_rate, w);
}

void filter_pass(const PassCrowd& c, const AgentFrame& frame, std::span<const glm::vec2> root_xz,
                 FilterState st, bool stand_through_jitter, SanitisedInput out,
                 std::span<float> out_speed, std::span<uint8_t> out_standing) {
  const MediatorParams& P = c.params;
  const bool apm = is_apm(c);
  // Without a level of detail every agent steps by dt_s: the springs' decays once for all.
  const bool one_step = c.step_s.empty();
  const SpringStep vel_step = spring_step(P.velocity_halflife_s, c.dt_s);
  const SpringStep theta_step = spring_step(P.theta_halflife_s, c.dt_s);
  const bool jitter_gate = apm && stand_through_jitter;
  const float still_a = 1.0f - std::exp(-c.dt_s / kStillAverageTime);
  const float reach = P.idle_step_distance_m;
  for_each_agent(c, [&](size_t i, int slot) {
    const float dt = c.dt(slot);
    // Sanitise what the simulator gave (NaN, absurd speeds): hold the last good values.
    const glm::vec2 p_in = frame.positions[i], v_in = frame.velocities[i];
    const glm::vec2 p = usable_position(p_in) ? p_in : root_xz[slot];
    glm::vec2 v = finite2(v_in) ? v_in : st.vel[slot];
    if (glm::length(v) > kAbsurdSpeed) v = st.vel[slot];
    const float theta_raw = std::isfinite(frame.thetas[i]) ? frame.thetas[i] : st.theta[slot];
    out.positions[i] = p;
    out.velocities[i] = v;
    out.thetas[i] = theta_raw;
    // Smoothed (APM only: the naive and rate modes take the simulator as it is), so a zig-zag of
    // the simulator never reaches the body.
    if (apm) {
      critical_spring(st.vel[slot], st.vel_rate[slot], v,
                      one_step ? vel_step : spring_step(P.velocity_halflife_s, dt));
      const float goal = st.theta[slot] + wrap_pi(theta_raw - st.theta[slot]);
      critical_spring(st.theta[slot], st.theta_rate[slot], goal,
                      one_step ? theta_step : spring_step(P.theta_halflife_s, dt));
    } else {
      st.vel[slot] = v;
      st.theta[slot] = theta_raw;
    }
    float speed = glm::length(st.vel[slot]);
    bool stand = speed < P.stop_speed_m_s;
    uint8_t held = 0;
    if (jitter_gate) {
      if (usable_position(p_in)) {
        glm::vec2& at = st.still_at[slot];
        float& jitter2 = st.still_jitter2[slot];
        if (c.fresh[slot] || jitter2 < 0.0f) {  // new, or the gate was off: nothing known yet
          at = p;
          jitter2 = 0.0f;
        }
        const bool stood = !c.fresh[slot] && out_standing[slot] != 0;
        const float a = one_step ? still_a : 1.0f - std::exp(-dt / kStillAverageTime);
        // How far p may stray from where it stands and still be jitter: no further than a
        // standing body's feet reach without a step (idle_step_distance_m), so a start is let go
        // by then at the latest, whatever the jitter seen.
        const float r = std::min(kStartJitterSigmas * std::sqrt(jitter2), reach);
        if (stood) {
          const glm::vec2 off = p - at;
          const float d2 = glm::dot(off, off);
          if (!stand && d2 < r * r) {
            stand = true;  // it stays where it stands: jitter, not a start
            speed = 0.0f;
            held = 1;
          }
          // The jitter about where it stands, over every frame it stands; a frame adds no more
          // than the reach, so a start it holds cannot raise the limit past it.
          jitter2 += (std::min(d2, reach * reach) - jitter2) * a;
        }
        if (stand && !stood) {
          // Stopped somewhere new: it stands here. Back within twice its hold of where it stood
          // before (a wobble let go as a start that went nowhere), that place stays, its average
          // kept; a clean track (no jitter, no hold) always stands where it stopped.
          const glm::vec2 off = p - at;
          if (glm::dot(off, off) > 4.0f * r * r) at = p;
        } else if (stand && !held) {
          at += (p - at) * a;  // where it stands moves with a slow p, not with a held one
        }
      }  // an unusable p leaves the state as it was
      st.jitter_held[slot] = held;
    }
    out_speed[slot] = speed;
    out_standing[slot] = stand;
  });
}

void root_pass(const PassCrowd& c, std::span<const glm::vec2> positions,
               std::span<const glm::vec2> vel_in, std::span<const uint8_t> standing,
               std::span<const float> lower_yaw, std::span<glm::vec2> root_xz,
               std::span<float> out_root_heading, std::span<const SupportReach> support_reach,
               bool honoured, std::span<float> root_speed, std::span<glm::vec2> out_hold,
               std::span<float> out_hold_scale, std::span<const glm::vec2> still_at,
               std::span<const uint8_t> jitter_held) {
  const bool apm = is_apm(c);
  const bool one_step = c.step_s.empty();  // every agent steps by dt_s: one exp for all
  const float pull = root_pull(c.dt_s);
  for_each_agent(c, [&](size_t i, int slot) {
    const float dt = c.dt(slot);
    // Predicted with the filtered velocity and pulled onto p, so a simulator's frame-to-frame
    // jitter (velocity flips in a jam) does not shake the body, while a steady walk is tracked
    // without lag. Never more than kMaxRootOffset from p. The legs then walk where the drawn root
    // really goes.
    const glm::vec2 p = positions[i];
    const glm::vec2 vel = vel_in[slot];
    glm::vec2 root_vel = vel;
    out_hold[slot] = glm::vec2(0.0f);
    out_hold_scale[slot] = 1.0f;
    if (apm && !c.fresh[slot]) {
      const bool held = !jitter_held.empty() && jitter_held[slot];
      const float k = one_step ? pull : root_pull(dt);
      glm::vec2 root = held ? held_root(root_xz[slot], still_at[slot], p, dt, k)
                            : pulled_root(root_xz[slot], vel, p, dt, k);
      // A foot that carries the body alone holds it back (a source that takes feedback only:
      // one that does not would just be caught up with later). Until the other foot comes down
      // the root may cover what is left of the support leg's reach, no more: its speed away from
      // the foot is cut to that gap over the time to the landing (with no landing in sight, to
      // what still stops it at the edge braking at kSupportBrake), the whole step scaled so the
      // body keeps its direction, and never braked harder than kSupportBrake (beyond, the foot
      // gives, as before); never backward, never further than kMaxRootOffset from p. The
      // simulator is given the held position and the speed the body kept (feedback_pass).
      if (honoured && c.params.support_hold && !support_reach.empty() &&
          support_reach[slot].radius >= 0.0f) {
        const SupportReach& sr = support_reach[slot];
        const glm::vec2 prev = root_xz[slot];
        const glm::vec2 from_foot = prev - sr.centre;
        const float dist = glm::length(from_foot);
        const glm::vec2 step = root - prev;
        const float away = dist > 1e-6f ? glm::dot(step, from_foot) / dist : 0.0f;
        const float gap = std::max(0.0f, sr.radius - dist);
        float allowed;
        if (sr.landing_s >= 0.0f) {
          allowed = sr.landing_s > dt ? gap * dt / sr.landing_s : gap;
        } else {
          // The speed from which braking frame by frame covers the gap: v dt + (v - a dt) dt +
          // ... = v^2 / 2a + v dt / 2.
          const float half = 0.5f * kSupportBrake * dt;
          allowed =
              std::min(gap, (std::sqrt(half * half + 2.0f * kSupportBrake * gap) - half) * dt);
        }
        if (away > allowed) {
          // No harder a brake than kSupportBrake from the root's own speed last frame.
          const float speed = glm::length(step) / dt;
          const float floor_speed = root_speed[slot] - kSupportBrake * dt;
          const float scale = std::clamp(
              std::max(allowed / away, speed > 1e-4f ? floor_speed / speed : 0.0f), 0.0f, 1.0f);
          out_hold_scale[slot] = scale;
          const glm::vec2 held = near_p(prev + step * scale, p);
          out_hold[slot] = held - root;
          root = held;
        }
      }
      root_vel = (root - root_xz[slot]) / dt;
      root_xz[slot] = root;
    } else {
      root_xz[slot] = p;
    }
    const float speed = glm::length(root_vel);
    root_speed[slot] = speed;
    out_root_heading[slot] =
        standing[slot] ? lower_yaw[slot] : heading2(speed > 1e-3f ? root_vel : vel);
  });
}

void facing_pass(const PassCrowd& c, std::span<const float> root_heading,
                 std::span<const float> theta_unwrapped, std::span<const uint8_t> standing_in,
                 std::span<float> lower_target, std::span<float> lower_yaw,
                 std::span<float> lower_yaw_rate, std::span<float> out_upper_yaw,
                 std::span<float> out_rel_dir, std::span<const int16_t> layer_clip,
                 std::span<const float> layer_weight) {
  const LocomotionLibrary& lib = c.library;
  const MediatorParams& P = c.params;
  const bool apm = is_apm(c);
  for_each_agent(c, [&](size_t, int slot) {
    const float dt = c.dt(slot);
    // The lower body follows v (or a strafe/backward orientation), the upper body faces theta.
    const float travel = root_heading[slot];
    const float theta = wrap_pi(theta_unwrapped[slot]);
    const bool standing = standing_in[slot];
    float psi = lower_yaw[slot];
    if (!apm) {
      psi = standing ? psi : travel;
    } else {
      float target = travel;
      if (standing) {
        target = theta;
      } else if (lib.has_direction_clips()) {
        // Pick the travel-direction group that leaves the upper body the least twist.
        const float current_d = wrap_pi(travel - lower_target[slot]);
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
      // The gait clips played travel a few degrees off their group's direction (a captured walk
      // drifts): the lower body faces that much the other way, so the legs walk along v. From the
      // layers as last planned (the weights follow the speed, not the facing).
      if (!standing) {
        float off = 0.0f, wsum = 0.0f;
        for (int k = 0; k < kMaxBlendLayers; ++k) {
          const float lw = layer_weight[slot * kMaxBlendLayers + k];
          const LocomotionClip& clip = lib.clips[layer_clip[slot * kMaxBlendLayers + k]];
          if (!clip.gait || !(lw > 0.0f)) continue;
          off += lw * clip.direction_offset_rad;
          wsum += lw;
        }
        if (wsum > 0.0f) target -= off / wsum;
      }
      lower_target[slot] = target;
      // The turn speeds up and slows down (lower_turn_accel_deg_s2): a jam's zig-zagging
      // velocity never reverses it in a frame. (Not also the target's own turn rate fed
      // forward: the body then followed the jitter again.)
      const float rate = glm::radians(P.lower_turn_rate_deg_s) * (standing ? 0.5f : 1.0f);
      turn_toward(psi, lower_yaw_rate[slot], target, rate, glm::radians(P.lower_turn_accel_deg_s2),
                  dt);
    }
    lower_yaw[slot] = psi;
    out_upper_yaw[slot] = apm ? theta : psi;
    out_rel_dir[slot] = standing || !apm ? 0.0f : wrap_pi(travel - psi);
  });
}

void weights_pass(const PassCrowd& c, std::span<const float> speed_m_s,
                  std::span<const float> rel_dir, std::span<const float> min_cadence,
                  ClipWeights cw, std::span<int16_t> layer_clip, std::span<float> layer_weight,
                  std::span<float> out_blend_progress) {
  const LocomotionLibrary& lib = c.library;
  const MediatorParams& P = c.params;
  const size_t nc = lib.clips.size();
  const bool apm = is_apm(c);
  for_each_agent(c, [&](size_t, int slot) {
    const float dt = c.dt(slot);
    // Target blend weights, faded toward over the blend time (APM) or switched at once.
    const std::span<float> w = cw.faded.subspan(slot * nc, nc);
    const std::span<float> target_w = cw.target.subspan(slot * nc, nc);
    choose_clip_weights(lib, P, speed_m_s[slot], rel_dir[slot], target_w, min_cadence[slot]);
    if (apm && !c.fresh[slot]) {
      const float step = dt / P.blend_time_s;
      float diff = 0.0f;
      for (size_t k = 0; k < nc; ++k) {
        w[k] = approach(w[k], target_w[k], step);
        diff += std::abs(target_w[k] - w[k]);
      }
      out_blend_progress[slot] = 1.0f - 0.5f * diff;
    } else {
      std::copy(target_w.begin(), target_w.end(), w.begin());
      out_blend_progress[slot] = 1.0f;
    }
    // Keep the kMaxBlendLayers heaviest clips, normalised.
    int16_t* lc = &layer_clip[slot * kMaxBlendLayers];
    float* lw = &layer_weight[slot * kMaxBlendLayers];
    std::fill(lw, lw + kMaxBlendLayers, 0.0f);
    for (size_t k = 0; k < nc; ++k) {
      if (w[k] <= 1e-4f) continue;
      int k_min = 0;
      for (int l = 1; l < kMaxBlendLayers; ++l) {
        if (lw[l] < lw[k_min]) k_min = l;
      }
      if (w[k] > lw[k_min]) {
        lw[k_min] = w[k];
        lc[k_min] = static_cast<int16_t>(k);
      }
    }
    float total = 0.0f;
    for (int l = 0; l < kMaxBlendLayers; ++l) total += lw[l];
    if (total <= 0.0f) {
      lw[0] = 1.0f;
      lc[0] = static_cast<int16_t>(lib.idle);
      total = 1.0f;
    }
    for (int l = 0; l < kMaxBlendLayers; ++l) lw[l] /= total;
  });
}

GaitFrequency gait_frequency(const LocomotionLibrary& lib, const int16_t* lc, const float* lw) {
  GaitFrequency out;
  for (int k = 0; k < kMaxBlendLayers; ++k) {
    const LocomotionClip& clip = lib.clips[lc[k]];
    if (clip.gait && lw[k] > 0.0f) {
      out.cycles_per_s += lw[k] / clip.cycle_s;
      out.gait_weight += lw[k];
    }
  }
  if (out.gait_weight > 0.0f) out.cycles_per_s /= out.gait_weight;
  return out;
}

namespace {

// The factor on an agent's playback rate that brings its swinging foot down before the body has
// gone beyond the reach of the foot that carries it alone (ReachInput, SupportReach), eased in
// and out over kReachBoostTime; 1 while no foot carries the body alone or the landing comes in
// time. A walker speeding up takes quicker steps: the swing ends sooner, rather than the
// stance leg being overstretched, let go and re-pinned (the feet gliding or both in the air)
// before the other foot lands.
float reach_boost(const PassCrowd& c, const ReachInput& reach, int slot, float rate,
                  float played_rate, float dt) {
  float& boost = reach.boost[slot];
  float goal = 1.0f;
  if (!reach.support_reach.empty()) {
    const SupportReach& sr = reach.support_reach[slot];
    // (A re-planting step lands on its own clock: a faster gait does not bring it down sooner.)
    if (sr.radius >= 0.0f && sr.landing_s > 0.0f && !sr.replanting) {
      // Last frame's landing time, at the rate played then: at this frame's plain rate, and a
      // frame on.
      const float landing_s = std::max(sr.landing_s * played_rate / rate - dt, 0.0f);
      const glm::vec2 from = reach.root_xz[slot] - sr.centre;
      const float dist = glm::length(from);
      // The body's speed away from the foot (the simulator's, filtered: a frame's jitter of the
      // drawn root is no reason to step faster), and the time until it leaves the reach.
      const float away = dist > 1e-4f ? glm::dot(reach.velocity[slot], from) / dist : 0.0f;
      if (away > 1e-3f) {
        const float leaves_s = std::max(sr.radius - dist, 0.0f) / away;
        if (leaves_s < landing_s) goal = landing_s / std::max(leaves_s, dt);
      }
    }
  }
  const float most = std::max(1.0f, c.params.max_playback_rate / rate);
  goal = std::clamp(goal, 1.0f, most);
  // From 1 to the fastest rate over kReachBoostTime at the most, at an even pace.
  boost = approach(boost, goal, (c.params.max_playback_rate - 1.0f) * dt / kReachBoostTime);
  return boost;
}

}  // namespace

void rate_phase_pass(const PassCrowd& c, std::span<const int16_t> layer_clip,
                     std::span<const float> layer_weight, std::span<const float> speed_m_s,
                     std::span<const float> cadence_scale, std::span<const float> lower_yaw,
                     std::span<const float> transition_weight, ReachInput reach,
                     std::span<float> phase, std::span<float> idle_time_s,
                     std::span<float> out_playback_rate, std::span<float> out_gait_weight,
                     std::span<float> out_travel_yaw) {
  const LocomotionLibrary& lib = c.library;
  const MediatorParams& P = c.params;
  for_each_agent(c, [&](size_t, int slot) {
    const float dt = c.dt(slot);
    // Playback rate from speed, within limits; beyond them the deliverable speed goes back to
    // the simulator (feedback_pass, with the stride stretch MediatorParams::max_stride_warp
    // allows, none by default).
    const int16_t* lc = &layer_clip[slot * kMaxBlendLayers];
    const float* lw = &layer_weight[slot * kMaxBlendLayers];
    const GaitFrequency gf = gait_frequency(lib, lc, lw);
    const float freq = gf.cycles_per_s, gait_w = gf.gait_weight;
    float native = 0.0f;
    glm::vec2 dir_sum(0.0f);
    for (int k = 0; k < kMaxBlendLayers; ++k) {
      const LocomotionClip& clip = lib.clips[lc[k]];
      native += lw[k] * clip.speed_m_s;
      if (clip.gait && lw[k] > 0.0f) {
        dir_sum += lw[k] * glm::vec2(std::sin(clip.direction_rad), std::cos(clip.direction_rad));
      }
    }
    float rate = 1.0f;
    if (gait_w > 0.0f && out_gait_weight[slot] <= 0.0f && !(transition_weight[slot] > 0.0f) &&
        !c.fresh[slot] && is_apm(c)) {
      // Setting off from standing (the gait clips were out of the blend, so their phase was not
      // seen): from where a foot of the heaviest gait clip leaves the ground, so the first step
      // is a whole swing that lifts the foot, not the end of one that slides it in. (A start or
      // stop clip drives the phase itself while it plays.)
      int heaviest = -1;
      for (int k = 0; k < kMaxBlendLayers; ++k) {
        if (lib.clips[lc[k]].gait && lw[k] > 0.0f && (heaviest < 0 || lw[k] > lw[heaviest])) {
          heaviest = k;
        }
      }
      const float* lift = lib.clips[lc[heaviest]].lift_phase;
      float best = -1.0f, best_ahead = 2.0f;
      for (int s = 0; s < 2; ++s) {
        if (lift[s] < 0.0f) continue;
        float ahead = lift[s] - phase[slot];
        ahead -= std::floor(ahead);
        if (ahead < best_ahead) {
          best_ahead = ahead;
          best = lift[s];
        }
      }
      if (best >= 0.0f) phase[slot] = best;
    }
    // Quicker steps: in APM, not for a new agent (its slot's reach is the previous agent's), nor
    // while a start or stop plays (its own clock lands the feet); the factor is 1 otherwise.
    const bool quicken = P.quicken_steps && is_apm(c) && !c.fresh[slot] &&
                         !(transition_weight[slot] > 0.0f) && gait_w > 0.0f;
    if (!quicken) reach.boost[slot] = 1.0f;
    if (gait_w > 0.0f) {
      if (P.mode == MediatorMode::kNaive) {
        rate = 1.0f;
      } else if (native > 1e-3f) {
        rate = std::clamp(speed_m_s[slot] / native * cadence_scale[slot], P.min_playback_rate,
                          P.max_playback_rate);
        if (quicken) {
          const float played = out_playback_rate[slot];  // last frame's, overwritten below
          rate = std::clamp(rate * reach_boost(c, reach, slot, rate, played, dt),
                            P.min_playback_rate, P.max_playback_rate);
        }
      }
      phase[slot] = near_fmod(phase[slot] + freq * rate * dt, 1.0f);
    }
    idle_time_s[slot] += dt;
    out_playback_rate[slot] = gait_w > 0.0f ? rate : 1.0f;
    out_gait_weight[slot] = gait_w;
    // Forward clips alone sum to (+-0, y > 0), whose atan2 is that zero: no call for them.
    const bool ahead = dir_sum.x == 0.0f && dir_sum.y > 0.0f;
    out_travel_yaw[slot] =
        wrap_pi(lower_yaw[slot] +
                (gait_w > 0.0f ? (ahead ? dir_sum.x : std::atan2(dir_sum.x, dir_sum.y)) : 0.0f));
  });
}

namespace {

// The transition an agent starts or stops with: the one of `kind` whose moving speed is nearest
// `speed` (-1: the library has none).
int nearest_transition(const LocomotionLibrary& lib, TransitionKind kind, float speed) {
  int best = -1;
  float best_d = 0.0f;
  for (size_t i = 0; i < lib.transitions.size(); ++i) {
    const Transition& t = lib.transitions[i];
    if (t.kind != kind) continue;
    const float d = std::abs(t.moving_speed_m_s - speed);
    if (best < 0 || d < best_d) {
      best = static_cast<int>(i);
      best_d = d;
    }
  }
  return best;
}

// True when the phase passed `target` going from `from` to `to` (forward, less than a cycle).
bool phase_passed(float from, float to, float target) {
  float span = to - from;
  if (span < 0.0f) span += 1.0f;
  float off = target - from;
  if (off < 0.0f) off += 1.0f;
  return off <= span && span < 0.5f;
}

}  // namespace

void transition_pass(const PassCrowd& c, std::span<const float> speed_m_s,
                     std::span<const float> playback_rate, std::span<const uint8_t> standing,
                     std::span<int16_t> layer_clip, std::span<float> layer_weight,
                     std::span<float> gait_weight, std::span<float> phase, TransitionState st) {
  const LocomotionLibrary& lib = c.library;
  const MediatorParams& P = c.params;
  const bool play = is_apm(c) && !lib.transitions.empty();
  const float kStill = SegmentationThresholds{}.idle_speed_m_s;  // [m/s] a root this slow stands
  constexpr float kLagCatchUp = 0.3f;  // [s] a transition's clip makes up its root's lag this fast
  for_each_agent(c, [&](size_t, int slot) {
    const float dt = c.dt(slot);
    const float v = speed_m_s[slot];
    const bool stand = standing[slot] != 0;
    uint32_t* counts = &st.counts[static_cast<size_t>(slot) * kNumCounts];
    if (c.fresh[slot]) {
      st.index[slot] = -1;
      st.stage[slot] = TransitionStage::kNone;
      st.weight[slot] = st.time_s[slot] = st.waited_s[slot] = st.lag_m[slot] = 0.0f;
      st.min_cadence[slot] = 0.0f;
      st.rate[slot] = 1.0f;
      st.still_s[slot] = st.moving_s[slot] = 0.0f;
      st.peak_speed_m_s[slot] = 0.0f;
      st.start_due[slot] = 0;
      st.prev_speed_m_s[slot] = v;
      st.prev_phase[slot] = phase[slot];
      return;
    }
    const float accel = (v - st.prev_speed_m_s[slot]) / dt;
    const float prev_phase = st.prev_phase[slot];
    st.prev_speed_m_s[slot] = v;
    const bool start_seen = !stand && st.still_s[slot] >= kTransitionSettle;
    const bool came_to_rest = stand && st.moving_s[slot] >= kTransitionSettle;
    // A stop from a walk: a creep (never as fast as a take's standing speed) has no step to stop.
    const bool stop_seen = came_to_rest && st.peak_speed_m_s[slot] >= kStill;
    if (came_to_rest && !stop_seen) ++counts[kCreepStops];
    if (stand) {
      st.still_s[slot] += dt;
      st.moving_s[slot] = 0.0f;
      st.peak_speed_m_s[slot] = 0.0f;
    } else {
      st.moving_s[slot] += dt;
      st.still_s[slot] = 0.0f;
      st.peak_speed_m_s[slot] = std::max(st.peak_speed_m_s[slot], v);
    }
    TransitionStage& stage = st.stage[slot];
    int16_t& index = st.index[slot];
    float& t = st.time_s[slot];
    float& w = st.weight[slot];
    const float fade = dt / P.blend_time_s;
    if (!play && stage != TransitionStage::kNone) {
      // The mode left APM (set_params): its other modes switch clips at once.
      stage = TransitionStage::kNone;
      index = -1;
      w = 0.0f;
      st.min_cadence[slot] = 0.0f;
    }
    if (stop_seen) ++counts[kStopsSeen];
    if (start_seen) ++counts[kStartsSeen];
    // A start seen as a stop faded out begins once it has gone, unless the agent stands again.
    uint8_t& start_due = st.start_due[slot];
    if (stand) start_due = 0;
    const bool start_late = start_due != 0 && stage == TransitionStage::kNone;
    if (start_seen || start_late) {
      // Played unless a stop is still playing or fading out (one waiting for its phase gives
      // way); then as soon as it has gone, from where the clip moves as fast as the agent.
      const int k = play ? nearest_transition(lib, TransitionKind::kStart, v) : -1;
      const bool free = stage == TransitionStage::kNone || stage == TransitionStage::kWaiting;
      start_due = k >= 0 && !free ? 1 : 0;
      if (k >= 0 && free) {
        const Transition& tr = lib.transitions[k];
        index = static_cast<int16_t>(k);
        stage = TransitionStage::kPlaying;
        w = 0.0f;
        // From where the clip moves as fast as the agent (its rest before that is skipped).
        t = tr.moving_from_s;
        while (t < tr.moving_to_s && tr.speed_at(t) < v) t += 1.0f / tr.fps;
        st.lag_m[slot] = 0.0f;
        ++counts[kStartsPlayed];
      }
    }
    if (play && stage == TransitionStage::kNone && !stand &&
        st.moving_s[slot] >= kTransitionSettle && accel < -kStopDeceleration) {
      // Slowing down: a stop when the speed, falling as it does, reaches rest within the stop
      // clip's own stopping time (with some slack), from a speed the clip walks at.
      // It is entered where the clip has slowed to the agent's speed (a slow agent plays only
      // the stop's last steps), or later where the clip is slower still but the agent can play
      // it and still come to rest in time. The stop nearest in speed, or its mirror image (the
      // same stop ending on the other foot), at the entry whose step comes soonest in the gait,
      // so the agent waits at most about a step for it (an agent in a jam that slows to rest in
      // a step or two would otherwise stand before its stop begins).
      const int nearest = nearest_transition(lib, TransitionKind::kStop, v);
      const float near_v = nearest >= 0 ? lib.transitions[nearest].moving_speed_m_s : 0.0f;
      const float to_rest = v / -accel;
      int k = -1;
      float k_entry = 0.0f, k_wait = 0.0f;
      for (size_t i = 0; i < lib.transitions.size() && nearest >= 0; ++i) {
        const Transition& tr = lib.transitions[i];
        if (tr.kind != TransitionKind::kStop ||
            std::abs(tr.moving_speed_m_s - near_v) > 0.01f * near_v) {
          continue;
        }
        float entry = tr.moving_from_s;
        while (entry < tr.moving_to_s && tr.speed_at(entry) > v) entry += 1.0f / tr.fps;
        if (!(to_rest <= 1.25f * (tr.moving_to_s - entry) + 0.2f &&
              v <= 1.3f * tr.moving_speed_m_s && entry < tr.moving_to_s)) {
          continue;
        }
        // Later entries, where the clip is slower still, as long as the agent can play them
        // (its speed within the clip's at the fastest rate) and still comes to rest in time.
        const float frame = 1.0f / tr.fps;
        float last = entry;
        while (last + frame < tr.moving_to_s &&
               tr.speed_at(last + frame) * P.max_playback_rate >= v &&
               to_rest <= 1.25f * (tr.moving_to_s - last - frame) + 0.2f) {
          last += frame;
        }
        for (float e = entry; e <= last + 1e-4f; e += frame) {
          float wait = tr.phase_at(e) - phase[slot];
          wait -= std::floor(wait);
          if (k < 0 || wait < k_wait) {
            k = static_cast<int>(i);
            k_wait = wait;
            k_entry = e;
          }
        }
      }
      if (k >= 0) {
        index = static_cast<int16_t>(k);
        stage = TransitionStage::kWaiting;
        st.waited_s[slot] = 0.0f;
        // A walker who has chosen to stop keeps the cadence to the step the stop begins on
        // (the slowing shortens the steps, as the stop clip then does): the weights hold it.
        // (Without the reach's quickening: that is for the step in the air, not the cadence.)
        st.min_cadence[slot] =
            playback_rate[slot] / (st.rate_boost.empty() ? 1.0f : st.rate_boost[slot]);
        st.chosen_speed_m_s[slot] = v;
        t = k_entry;
        w = 0.0f;
      }
    }
    if (stage == TransitionStage::kNone) {
      st.prev_phase[slot] = phase[slot];
      return;
    }
    const Transition& tr = lib.transitions[index];
    const LocomotionClip& cycle = lib.clips[tr.cycle_clip];
    const bool start = tr.kind == TransitionKind::kStart;
    if (stage == TransitionStage::kWaiting) {
      // The stop begins on the gait phase its first landing matches; it is given up if the agent
      // walks on (faster than when it chose the stop: a frame's rise of a speed that jitters
      // while it slows, as in a jam, is not), stands before that phase comes, or the phase does
      // not come within a cycle at the held cadence (the agent is not walking).
      st.waited_s[slot] += dt;
      const float entry_phase = tr.phase_at(t);
      const float cycle_time =
          cycle.cycle_s / std::max(st.min_cadence[slot], P.min_playback_rate) + 0.1f;
      if (v > st.chosen_speed_m_s[slot] || stand || st.waited_s[slot] > cycle_time) {
        stage = TransitionStage::kNone;
        index = -1;
        st.min_cadence[slot] = 0.0f;
      } else if (phase_passed(prev_phase, phase[slot], entry_phase)) {
        stage = TransitionStage::kPlaying;
        st.min_cadence[slot] = 0.0f;
        float late = phase[slot] - entry_phase;
        if (late < 0.0f) late += 1.0f;
        t = std::min(t + late / tr.phase_rate_at(t), tr.duration_s);
        st.lag_m[slot] = 0.0f;
        w = 0.0f;
      }
      if (stage != TransitionStage::kPlaying) {
        st.prev_phase[slot] = phase[slot];
        return;
      }
    } else {
      // The clock: the agent's speed over the clip's root speed, within the rate limits (where
      // both stand, the clip settles at its own pace).
      const float clip_v = tr.speed_at(t);
      float rate = 1.0f;
      if (clip_v >= kStill || v >= kStill) {
        // The agent's speed, plus what the clip's root has fallen behind it (made up over
        // kLagCatchUp), over the clip's.
        const float wanted = v + st.lag_m[slot] / kLagCatchUp;
        rate =
            std::clamp(wanted / std::max(clip_v, 0.05f), P.min_playback_rate, P.max_playback_rate);
        // A stop whose clip still walks faster than the agent hurries on to where it is as slow.
        if (!start && clip_v > 1.15f * v + 0.05f) rate = P.max_playback_rate;
      }
      st.rate[slot] = rate;
      const float t_next = std::min(t + rate * dt, tr.duration_s);
      st.lag_m[slot] += v * dt - clip_v * (t_next - t);
      t = t_next;
    }
    if (stage == TransitionStage::kPlaying) {
      // Left when it is nearly over (a start hands over to the cycle while the clip still walks,
      // a stop once the clip stands), or when the agent does the opposite of what it plays.
      const bool over = start ? t >= tr.duration_s - P.blend_time_s * st.rate[slot]
                              : t >= tr.duration_s - P.blend_time_s;
      // A stop is also left when the agent walks on faster than the clip can follow.
      const float reach = tr.speed_at(t) * P.max_playback_rate + kStill;
      // A start is left when the agent stops again or creeps on slower than the clip can go.
      const bool creeps = tr.speed_at(t) * P.min_playback_rate > v + kStill;
      const bool aborted =
          start ? stand || creeps
                : !stand &&
                      ((accel > kStopDeceleration && v > 0.5f * tr.moving_speed_m_s) || v > reach);
      if (over || aborted) stage = TransitionStage::kLeaving;
    }
    if (stop_seen && !start) ++counts[kStopsPlayed];  // the agent comes to rest in a stop clip
    w = stage == TransitionStage::kPlaying ? std::min(1.0f, w + fade) : std::max(0.0f, w - fade);
    if (stage == TransitionStage::kLeaving && w <= 0.0f) {
      stage = TransitionStage::kNone;
      index = -1;
      st.prev_phase[slot] = phase[slot];
      return;
    }
    // The gait phase follows the transition's own steps: the cycle joins (or leaves) in step.
    phase[slot] = tr.phase_at(t);
    st.prev_phase[slot] = phase[slot];
    // The transition's layer takes a free one (a forward-only blend fills at most two of them,
    // plus clips fading out); until one is free its weight waits at 0 (a layer dropped at once
    // would pop), then the others share 1 - w.
    int16_t* lc = &layer_clip[slot * kMaxBlendLayers];
    float* lw = &layer_weight[slot * kMaxBlendLayers];
    int k_min = 0;
    for (int l = 1; l < kMaxBlendLayers; ++l) {
      if (lw[l] < lw[k_min]) k_min = l;
    }
    if (lw[k_min] > 1e-4f && w <= fade) {
      w = 0.0f;
      return;
    }
    lw[k_min] = 0.0f;
    float rest = 0.0f;
    for (int l = 0; l < kMaxBlendLayers; ++l) rest += lw[l];
    // The fade eases in and out: a weight that changes at a constant rate starts and stops its
    // change at once, and every joint's velocity jumps by the two poses' difference over the fade
    // time (a limb snaps as a stop the agent walks out of fades away).
    const float wl = smoothstep01(w);
    float gait = 0.0f;
    for (int l = 0; l < kMaxBlendLayers; ++l) {
      lw[l] = rest > 0.0f ? lw[l] * (1.0f - wl) / rest : 0.0f;
      if (l != k_min && lib.clips[lc[l]].gait) gait += lw[l];
    }
    lc[k_min] = static_cast<int16_t>(tr.clip);
    lw[k_min] = rest > 0.0f ? wl : 1.0f;
    gait_weight[slot] = gait;
  });
}

void contacts_pass(const PassCrowd& c, std::span<const int16_t> layer_clip,
                   std::span<const float> layer_weight, std::span<const float> phase,
                   std::span<const float> idle_time_s, std::span<const float> transition_time_s,
                   std::span<const float> gait_weight, std::span<const float> playback_rate,
                   std::span<const float> transition_rate, std::span<float> out_layer_time_s,
                   ContactPlans out) {
  const LocomotionLibrary& lib = c.library;
  for_each_agent(c, [&](size_t, int slot) {
    const int16_t* lc = &layer_clip[slot * kMaxBlendLayers];
    const float* lw = &layer_weight[slot * kMaxBlendLayers];
    float* lt = &out_layer_time_s[slot * kMaxBlendLayers];
    const float gait_w = gait_weight[slot];
    // Clip times at the shared gait phase (phase-synchronised blending; a new clip starts in
    // phase). Foot flags are voted by the gait clips alone once they carry a quarter of the blend:
    // a standing clip's "both feet down" would otherwise keep a stepping foot locked while it
    // swings.
    float plant[2] = {0.0f, 0.0f}, hold[2] = {0.0f, 0.0f}, vote_w = 0.0f;
    float toe_gait[2] = {0.0f, 0.0f}, swing[2] = {0.0f, 0.0f}, walk = 0.0f;
    float toe_stand[2] = {0.0f, 0.0f}, stand_w[2] = {0.0f, 0.0f};
    float landing[2] = {0.0f, 0.0f}, landing_w[2] = {0.0f, 0.0f};
    float toe_speed[2] = {0.0f, 0.0f}, speed_w[2] = {0.0f, 0.0f};
    const float rate = playback_rate[slot], tr_rate = transition_rate[slot];
    // Gait phase per second (rate_phase_pass's), taken once a clip swings a foot: a gait clip's
    // time runs at its table's local slope times that.
    float phase_rate = -1.0f;
    float moving_w = gait_w;  // gait clips and a transition: they vote without the standing clip
    for (int k = 0; k < kMaxBlendLayers; ++k) {
      if (lib.clips[lc[k]].transition) moving_w += lw[k];
    }
    const bool gait_votes = moving_w >= kGaitVoteWeight;
    for (int k = 0; k < kMaxBlendLayers; ++k) {
      // Only the layers pose synthesis samples (weight > 0) have a clip time; a standing clip's
      // (an fmod of a clock that only grows) would otherwise be taken for every empty layer.
      if (lw[k] <= 0.0f) {
        lt[k] = 0.0f;
        continue;
      }
      const LocomotionClip& clip = lib.clips[lc[k]];
      lt[k] = layer_time(clip, phase[slot], idle_time_s[slot], transition_time_s[slot]);
      auto wrap = [&clip](int i) { return clip.wrap_frame(i); };
      const float ft = lt[k] * clip.clip.fps;
      // Toe heights between frames (a 24 or 30 fps clip must not step the foot every other
      // frame).
      const int f0 = static_cast<int>(std::floor(ft));
      const float fu = ft - static_cast<float>(f0);
      // The nearest frame: lround's, from the fraction (exact for ft >= 0) without the call.
      const int f =
          wrap(ft >= 0.0f ? f0 + (fu >= 0.5f ? 1 : 0) : static_cast<int>(std::lround(ft)));
      for (int s = 0; s < 2; ++s) {
        if (clip.toe_height_m[s].empty() || clip.transition) continue;
        if (clip.gait) {
          toe_gait[s] += lw[k] * clip.toe_y_at(s, f0, fu);
        } else {
          toe_stand[s] += lw[k] * clip.toe_y_at(s, f0, fu);
          stand_w[s] += lw[k];
        }
      }
      if (gait_votes && !clip.gait && !clip.transition) continue;
      // A gait clip runs at the playback rate, a transition at its own clock's.
      const float r = clip.transition ? tr_rate : clip.gait ? rate : 1.0f;
      vote_w += lw[k];
      if (clip.double_support) walk += lw[k];
      for (int s = 0; s < 2; ++s) {
        plant[s] += lw[k] * clip.plant[s][f];
        if (!clip.swing_progress[s].empty()) {
          // Between frames, as the toe heights (a 30 fps clip must not advance the swing, and the
          // release that follows it, every other frame); not across a landing, where it restarts.
          const auto& sp = clip.swing_progress[s];
          const float a = sp[wrap(f0)], b = sp[wrap(f0 + 1)];
          const float progress = b >= a ? a + fu * (b - a) : sp[f];
          swing[s] += lw[k] * progress;
          if (progress > 0.0f) {
            // This clip's swing: frame i of n at progress (i + 0.5) / n, so 1 / n a frame (from
            // its first frame or its last alone as well), and it lands at progress 1.
            const float per_frame = a > 0.0f ? (b > a ? b - a : 2.0f * (1.0f - a)) : 2.0f * b;
            float clip_rate = r;  // clip seconds per second
            if (clip.gait) {
              if (phase_rate < 0.0f) phase_rate = gait_frequency(lib, lc, lw).cycles_per_s * rate;
              clip_rate = clip.time_per_phase(phase[slot]) * phase_rate;
            }
            const float per_s = per_frame * clip.clip.fps * clip_rate;
            if (per_s > 0.0f) {
              landing[s] += lw[k] * (1.0f - progress) / per_s;
              landing_w[s] += lw[k];
            }
          }
        }
        hold[s] += lw[k] * clip.hold[s][f];
        if (!clip.toe_speed_m_s[s].empty()) {
          toe_speed[s] += lw[k] * clip.toe_speed_m_s[s][f] * r;
          speed_w[s] += lw[k];
        }
      }
    }
    for (int s = 0; s < 2; ++s) {
      out.plant[s][slot] = plant[s] / std::max(vote_w, 1e-6f);
      out.hold[s][slot] = hold[s] / std::max(vote_w, 1e-6f);
      out.swing_progress[s][slot] = swing[s] / std::max(vote_w, 1e-6f);
      out.landing_s[s][slot] = landing_w[s] > 0.0f ? landing[s] / landing_w[s] : -1.0f;
      out.gait_toe_y[s][slot] = gait_w > 0.0f ? toe_gait[s] / gait_w : 0.0f;
      out.stand_toe_y[s][slot] =
          stand_w[s] > 0.0f ? toe_stand[s] / stand_w[s] : std::numeric_limits<float>::lowest();
      out.clip_toe_speed[s][slot] = speed_w[s] > 0.0f ? toe_speed[s] / speed_w[s] : -1.0f;
    }
    out.double_support[slot] = walk / std::max(vote_w, 1e-6f);
    out.standing_votes[slot] = gait_votes ? 0 : 1;
  });
}

void feedback_pass(const PassCrowd& c, bool honoured, std::span<const glm::vec2> positions,
                   std::span<const glm::vec2> velocities, std::span<const float> thetas,
                   std::span<float> fed_speed, std::span<const float> lower_yaw,
                   std::span<const uint8_t> standing, std::span<const float> gait_weight,
                   std::span<const glm::vec2> hold, std::span<const float> hold_scale,
                   FeedbackOut out) {
  const LocomotionLibrary& lib = c.library;
  const MediatorParams& P = c.params;
  const bool apm = is_apm(c);
  for_each_agent(c, [&](size_t a, int slot) {
    // The speed and torso orientation the animation can deliver.
    glm::vec2 v = velocities[a];
    const float theta_raw = thetas[a];
    const float psi = lower_yaw[slot];
    out.has_feedback[a] = 0;
    out.positions[a] = positions[a];
    out.velocities[a] = v;
    out.thetas[a] = theta_raw;
    const float fed_before = fed_speed[slot];
    fed_speed[slot] = glm::length(v);
    if (!(apm && honoured)) return;
    // The root held back by a support foot (root_pass): the simulator's agent is held with it,
    // at the speed it kept (the speed-up below then starts from there: no lurch when it lets go).
    if (hold[slot] != glm::vec2(0.0f)) {
      out.positions[a] = positions[a] + hold[slot];
      v *= std::clamp(hold_scale[slot], 0.0f, 1.0f);
      out.velocities[a] = v;
      out.has_feedback[a] = 1;
    }
    const DirectionGroup& fg = lib.groups[lib.forward_group];
    const float max_speed =
        lib.clips[fg.clips.back()].speed_m_s * P.max_playback_rate * (1.0f + P.max_stride_warp);
    // Legs speed up over steps, not in a frame: a start from rest, or a jam clearing, is held to
    // the speed-up they deliver (above the speed the body has now).
    float v_len = glm::length(v);
    const float reachable = c.fresh[slot] ? v_len : fed_before + P.max_accel_m_s2 * c.dt(slot);
    if (v_len > reachable) {
      out.velocities[a] = v * (reachable / v_len);
      v_len = reachable;
      out.has_feedback[a] = 1;
    }
    if (v_len > max_speed) {
      out.velocities[a] *= max_speed / v_len;
      out.has_feedback[a] = 1;
    }
    // With forward clips only, the legs walk where the lower body faces, and it turns at a
    // limited rate: a velocity that turns faster is turned back to within turn_feedback_deg of
    // that facing, so the simulator moves the agent where its feet go (a jam's sideways jitter
    // would otherwise look like skating). A library with strafe or backward clips takes sideways
    // velocities by blending directions instead (and its facing may be mid-switch between
    // direction groups, which is no direction to hold the simulator to).
    const glm::vec2 v_out = out.velocities[a];
    const float v_out_len = glm::length(v_out);
    const float slack = glm::radians(P.turn_feedback_deg);
    if (!lib.has_direction_clips() && !standing[slot] && gait_weight[slot] > 0.0f &&
        v_out_len > P.stop_speed_m_s) {
      const float off = wrap_pi(heading2(v_out) - psi);  // its atan2 only where it can act
      if (std::abs(off) > slack) {
        const float dir = psi + std::clamp(off, -slack, slack);
        out.velocities[a] = v_out_len * glm::vec2(std::sin(dir), std::cos(dir));
        out.has_feedback[a] = 1;
      }
    }
    const float twist = wrap_pi(theta_raw - psi);
    const float limit = glm::radians(P.torsion_limit_deg);
    if (std::abs(twist) > limit && !lib.has_direction_clips()) {
      out.thetas[a] = wrap_pi(psi + std::clamp(twist, -limit, limit));
      out.has_feedback[a] = 1;
    }
    fed_speed[slot] = glm::length(out.velocities[a]);
  });
}

}  // namespace gk
