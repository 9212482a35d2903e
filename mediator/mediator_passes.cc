#include "mediator/mediator_passes.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <tbb/parallel_for.h>

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
void add_group_weights(const LocomotionLibrary& lib, const DirectionGroup& g, float speed,
                       float share, std::span<float> w) {
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

void choose_clip_weights(const LocomotionLibrary& lib, const MediatorParams& params, float speed,
                         float rel_dir, std::span<float> w) {
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

void filter_pass(const PassCrowd& c, const AgentFrame& frame, std::span<const glm::vec2> root_xz,
                 FilterState st, SanitisedInput out, std::span<float> out_speed,
                 std::span<uint8_t> out_standing) {
  const MediatorParams& P = c.params;
  const bool apm = is_apm(c);
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
      critical_spring(st.vel[slot], st.vel_rate[slot], v, P.velocity_halflife_s, dt);
      const float goal = st.theta[slot] + wrap_pi(theta_raw - st.theta[slot]);
      critical_spring(st.theta[slot], st.theta_rate[slot], goal, P.theta_halflife_s, dt);
    } else {
      st.vel[slot] = v;
      st.theta[slot] = theta_raw;
    }
    const float speed = glm::length(st.vel[slot]);
    out_speed[slot] = speed;
    out_standing[slot] = speed < P.stop_speed_m_s;
  });
}

void root_pass(const PassCrowd& c, std::span<const glm::vec2> positions,
               std::span<const glm::vec2> vel_in, std::span<const uint8_t> standing,
               std::span<const float> lower_yaw, std::span<glm::vec2> root_xz,
               std::span<float> out_root_heading) {
  const bool apm = is_apm(c);
  for_each_agent(c, [&](size_t i, int slot) {
    const float dt = c.dt(slot);
    // Predicted with the filtered velocity and pulled onto p, so a simulator's frame-to-frame
    // jitter (velocity flips in a jam) does not shake the body, while a steady walk is tracked
    // without lag. Never more than kMaxRootOffset from p. The legs then walk where the drawn root
    // really goes.
    const glm::vec2 p = positions[i];
    const glm::vec2 vel = vel_in[slot];
    glm::vec2 root_vel = vel;
    if (apm && !c.fresh[slot]) {
      const glm::vec2 root = pulled_root(root_xz[slot], vel, p, dt);
      root_vel = (root - root_xz[slot]) / dt;
      root_xz[slot] = root;
    } else {
      root_xz[slot] = p;
    }
    out_root_heading[slot] =
        standing[slot] ? lower_yaw[slot] : heading2(glm::length(root_vel) > 1e-3f ? root_vel : vel);
  });
}

void facing_pass(const PassCrowd& c, std::span<const float> root_heading,
                 std::span<const float> theta_unwrapped, std::span<const uint8_t> standing_in,
                 std::span<float> lower_target, std::span<float> lower_yaw,
                 std::span<float> out_upper_yaw, std::span<float> out_rel_dir) {
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
      lower_target[slot] = target;
      const float rate = glm::radians(P.lower_turn_rate_deg_s) * (standing ? 0.5f : 1.0f);
      psi = wrap_pi(approach_angle(psi, target, rate * dt));
    }
    lower_yaw[slot] = psi;
    out_upper_yaw[slot] = apm ? theta : psi;
    out_rel_dir[slot] = standing || !apm ? 0.0f : wrap_pi(travel - psi);
  });
}

void weights_pass(const PassCrowd& c, std::span<const float> speed_m_s,
                  std::span<const float> rel_dir, ClipWeights cw, std::span<int16_t> layer_clip,
                  std::span<float> layer_weight, std::span<float> out_blend_progress) {
  const LocomotionLibrary& lib = c.library;
  const MediatorParams& P = c.params;
  const size_t nc = lib.clips.size();
  const bool apm = is_apm(c);
  for_each_agent(c, [&](size_t, int slot) {
    const float dt = c.dt(slot);
    // Target blend weights, faded toward over the blend time (APM) or switched at once.
    const std::span<float> w = cw.faded.subspan(slot * nc, nc);
    const std::span<float> target_w = cw.target.subspan(slot * nc, nc);
    choose_clip_weights(lib, P, speed_m_s[slot], rel_dir[slot], target_w);
    if (apm && !c.fresh[slot]) {
      const float step = dt / P.blend_time_s;
      float diff = 0.0f;
      for (size_t k = 0; k < nc; ++k) {
        const float d = target_w[k] - w[k];
        w[k] += std::clamp(d, -step, step);
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

void rate_phase_pass(const PassCrowd& c, std::span<const int16_t> layer_clip,
                     std::span<const float> layer_weight, std::span<const float> speed_m_s,
                     std::span<const float> cadence_scale, std::span<const float> lower_yaw,
                     std::span<float> phase, std::span<float> idle_time_s,
                     std::span<float> out_playback_rate, std::span<float> out_gait_weight,
                     std::span<float> out_travel_yaw) {
  const LocomotionLibrary& lib = c.library;
  const MediatorParams& P = c.params;
  for_each_agent(c, [&](size_t, int slot) {
    const float dt = c.dt(slot);
    // Playback rate from speed, within limits; the rest is stride warping (foot IK), beyond that
    // the deliverable speed goes back to the simulator (feedback).
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
    if (gait_w > 0.0f) {
      if (P.mode == MediatorMode::kNaive) {
        rate = 1.0f;
      } else if (native > 1e-3f) {
        rate = std::clamp(speed_m_s[slot] / native * cadence_scale[slot], P.min_playback_rate,
                          P.max_playback_rate);
      }
      phase[slot] = std::fmod(phase[slot] + freq * rate * dt, 1.0f);
    }
    idle_time_s[slot] += dt;
    out_playback_rate[slot] = gait_w > 0.0f ? rate : 1.0f;
    out_gait_weight[slot] = gait_w;
    out_travel_yaw[slot] =
        wrap_pi(lower_yaw[slot] + (gait_w > 0.0f ? std::atan2(dir_sum.x, dir_sum.y) : 0.0f));
  });
}

void contacts_pass(const PassCrowd& c, std::span<const int16_t> layer_clip,
                   std::span<const float> layer_weight, std::span<const float> phase,
                   std::span<const float> idle_time_s, std::span<const float> gait_weight,
                   std::span<float> out_layer_time_s, ContactPlans out) {
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
    const bool gait_votes = gait_w >= 0.25f;
    for (int k = 0; k < kMaxBlendLayers; ++k) {
      const LocomotionClip& clip = lib.clips[lc[k]];
      lt[k] = layer_time(clip, phase[slot], idle_time_s[slot]);
      if (lw[k] <= 0.0f) continue;
      const int nf = clip.clip.num_frames;
      auto wrap = [&](int i) {
        return clip.clip.loops ? ((i % nf) + nf) % nf : std::clamp(i, 0, nf - 1);
      };
      const float ft = lt[k] * clip.clip.fps;
      const int f = wrap(static_cast<int>(std::lround(ft)));
      // Toe heights between frames (a 24 or 30 fps clip must not step the foot every other
      // frame).
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
        if (!clip.swing_progress[s].empty()) {
          // Between frames, as the toe heights (a 30 fps clip must not advance the swing, and the
          // release that follows it, every other frame); not across a landing, where it restarts.
          const auto& sp = clip.swing_progress[s];
          const float a = sp[wrap(f0)], b = sp[wrap(f0 + 1)];
          swing[s] += lw[k] * (b >= a ? a + fu * (b - a) : sp[f]);
        }
        hold[s] += lw[k] * clip.hold[s][f];
      }
    }
    for (int s = 0; s < 2; ++s) {
      out.plant[s][slot] = plant[s] / std::max(vote_w, 1e-6f);
      out.hold[s][slot] = hold[s] / std::max(vote_w, 1e-6f);
      out.swing_progress[s][slot] = swing[s] / std::max(vote_w, 1e-6f);
      out.gait_toe_y[s][slot] = gait_w > 0.0f ? toe_gait[s] / gait_w : 0.0f;
    }
    out.double_support[slot] = walk / std::max(vote_w, 1e-6f);
  });
}

void feedback_pass(const PassCrowd& c, bool honoured, std::span<const glm::vec2> positions,
                   std::span<const glm::vec2> velocities, std::span<const float> thetas,
                   std::span<float> fed_speed, std::span<const float> lower_yaw, std::span<const uint8_t> standing,
                   std::span<const float> gait_weight, FeedbackOut out) {
  const LocomotionLibrary& lib = c.library;
  const MediatorParams& P = c.params;
  const bool apm = is_apm(c);
  for_each_agent(c, [&](size_t a, int slot) {
    // The speed and torso orientation the animation can deliver.
    const glm::vec2 v = velocities[a];
    const float theta_raw = thetas[a];
    const float psi = lower_yaw[slot];
    out.has_feedback[a] = 0;
    out.positions[a] = positions[a];
    out.velocities[a] = v;
    out.thetas[a] = theta_raw;
    const float fed_before = fed_speed[slot];
    fed_speed[slot] = glm::length(v);
    if (!(apm && honoured)) return;
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
    const float off = wrap_pi(heading2(v_out) - psi);
    const float slack = glm::radians(P.turn_feedback_deg);
    if (!lib.has_direction_clips() && !standing[slot] && gait_weight[slot] > 0.0f &&
        v_out_len > P.stop_speed_m_s && std::abs(off) > slack) {
      const float dir = psi + std::clamp(off, -slack, slack);
      out.velocities[a] = v_out_len * glm::vec2(std::sin(dir), std::cos(dir));
      out.has_feedback[a] = 1;
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
