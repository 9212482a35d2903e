// Procedural gait: feet are planned in world space first (footprints, heel rocker, heel-off about
// the ball, swing arc), then the pelvis (constant-speed root motion plus bob, sway, rotation and
// obliquity), then each leg is solved with analytic two-bone IK and the upper body is layered on
// (spine counter-rotation, arm swing). Every quantity is a periodic function of the gait phase, so
// clips loop exactly apart from the root's advance.

#include "animation/gait_generator.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>

#include "animation/gait_curves.h"
#include "animation/gait_pose.h"

namespace gk {

using gait::deg;
using gait::kPi;
using gait::MonotoneCurve;

float walk_ratio_cadence(float speed_m_s) {
  const float v = std::max(speed_m_s, 0.05f);
  // Below 1 m/s the walk ratio shrinks linearly (to 0.6 x at standstill): shorter, quicker steps.
  const float ratio = v >= 1.0f ? 0.006f : 0.006f * (0.6f + 0.4f * v);
  return std::sqrt(60.0f * v / ratio);
}

int frames_per_stride(const GaitParams& params, float fps) {
  if (params.kind == GaitKind::kIdle)
    return std::max(1, int(std::lround(params.idle_duration_s * fps)));
  return std::max(8, int(std::lround(fps * 120.0f / params.cadence_steps_min)));
}

namespace gait {
namespace {

class GaitPlanner {
 public:
  GaitPlanner(const Skeleton& skeleton, const GaitParams& params, float stride_s)
      : skel_(skeleton),
        p_(params),
        rig_(skeleton),
        period_s_(stride_s),
        pitch_curve_(make_pitch_keys(), true),
        swing_curve_(make_swing_keys(), false) {
    travel_ = glm::length(p_.direction) > 0.0f ? glm::normalize(p_.direction) : glm::vec3(0, 0, 1);
    if (p_.reverse_time) travel_ = -travel_;  // planned forward, played backward
    stride_m_ = p_.speed_m_s * period_s_;
    if (p_.kind == GaitKind::kWalk || running()) {
      build_height_table();
    } else {
      pelvis_height_ = solve_pelvis_height();
    }
  }

  // Planner time of clip frame 0: a lateral-sway extremum, where the root's horizontal velocity
  // equals its mean, so extrapolating the mean velocity across the loop seam is exact.
  float time_origin() const {
    if (idle()) return 0.25f * period_s_;
    return side_step() ? 0.0f : 0.5f * beta() * period_s_;
  }

  // Local pose at planner time tau [s].
  void evaluate(float tau, glm::quat* out_rot, glm::vec3* out_trans) const {
    PoseTargets targets;
    pelvis(tau, &targets.root_position, &targets.pelvis_yaw, &targets.pelvis_roll);
    targets.root_position.y += pelvis_height_;
    if (!height_table_.empty()) targets.root_position.y = table_height(tau);
    for (int s = 0; s < 2; ++s) {
      const FootTarget f = foot(tau, s);
      targets.foot[s] = f;
      targets.ankle[s] = ankle_from_ball(f, s);
      targets.planted[s] = idle() || wrap01(tau / period_s_ - 0.5f * s) < beta();
    }
    upper_body(tau, &targets);
    build_local_pose(skel_, rig_, targets, out_rot, out_trans);
  }

 private:
  bool running() const { return p_.kind == GaitKind::kRun; }
  bool side_step() const { return p_.kind == GaitKind::kSideStep; }
  bool idle() const { return p_.kind == GaitKind::kIdle; }
  float beta() const { return p_.stance_fraction; }
  float foot_flat_phase() const { return 0.10f * beta(); }
  float heel_off_phase() const { return 0.55f * beta(); }

  std::vector<std::pair<float, float>> make_pitch_keys() const {
    if (idle() || side_step()) return {{0.0f, 0.0f}, {0.5f, 0.0f}};
    const float b = beta();
    const float swing_extra = running() ? 25.0f : 10.0f;
    // GAIT.md: the heel lifts while the ball stays planted; the ankle plantarflexes mostly in
    // pre-swing (push-off), so the heel rises slowly at first and quickly through push-off.
    const float late =
        running() ? heel_off_phase() + 0.8f * (b - heel_off_phase()) : 0.5f + 0.5f * (b - 0.5f);
    return {{0.0f, deg(p_.heel_strike_deg)},
            {foot_flat_phase(), 0.0f},
            {heel_off_phase(), 0.0f},
            {late, -deg((running() ? 0.3f : 0.5f) * p_.toe_off_deg)},
            {b, -deg(p_.toe_off_deg)},
            {b + 0.25f * (1.0f - b), -deg(p_.toe_off_deg + swing_extra)},
            {b + 0.75f * (1.0f - b), deg(0.3f * p_.heel_strike_deg)}};
  }
  // Ball height above its stance height over the swing. The foot leaves the ground pitched up by
  // the toe-off angle about its toe tip, so the ball starts the swing as high as that pitch puts
  // it (toe length x sin(toe-off)) and quickly, before the foot travels; likewise the last few
  // percent of the swing only lower the foot onto its landing height: it arrives from above.
  std::vector<std::pair<float, float>> make_swing_keys() const {
    const float land = landing_ball_height() - rig_.foot[0].ball_height_m;
    const float off = rig_.foot[0].toe_length_m * std::sin(deg(p_.toe_off_deg));
    return {{0.0f, 0.0f},
            {0.07f, std::min(off, p_.swing_peak_m)},
            {0.3f, p_.swing_peak_m},
            {0.65f, std::max(p_.swing_mid_m, land + off)},
            {0.94f, std::max(land, off)},
            {1.0f, land}};
  }

  // Ball height when the heel touches the ground with the foot pitched toe-up by the strike angle.
  float landing_ball_height() const { return heel_contact_ball_height(deg(p_.heel_strike_deg), 0); }
  float heel_contact_ball_height(float pitch, int side) const {
    const FootShape& fs = rig_.foot[side];
    const glm::vec3 heel_from_ball(0.0f, -fs.ball_height_m, -fs.heel_back_m - fs.ball_forward_m);
    const glm::vec3 rotated = pitch_q(-pitch) * heel_from_ball;
    return std::max(fs.ball_height_m, -rotated.y);
  }

  glm::quat pitch_q(float angle) const { return glm::angleAxis(angle, glm::vec3(1, 0, 0)); }

  glm::vec3 ankle_from_ball(const FootTarget& f, int side) const {
    return f.ball - pitch_q(-f.pitch) * rig_.ball_offset[side];
  }

  // Ball position of the footprint for stance number k of foot `side`.
  glm::vec3 footprint(int k, int side) const {
    const float sign = side == 0 ? 1.0f : -1.0f;
    glm::vec3 ankle(0.0f);
    if (idle()) {
      ankle = glm::vec3(sign * p_.foot_lateral * rig_.hip_offset[0].x, 0.0f, 0.0f);
    } else if (side_step()) {
      // Step-close: the lead (left) foot lands wide, the trail foot closes to a narrow stance.
      const float narrow = 1.1f * p_.foot_lateral * rig_.hip_offset[0].x;
      const float along = side == 0 ? stride_m_ * k + 0.5f * (narrow + stride_m_)
                                    : stride_m_ * (k + 0.5f) - 0.5f * narrow;
      ankle = along * travel_;
    } else {
      // The hip passes over the ankle at this fraction of the cycle after initial contact.
      const float over = running() ? 0.35f * beta() : 0.40f * beta();
      const float along = stride_m_ * (k + 0.5f * side + over);
      ankle = along * travel_ + glm::vec3(sign * p_.foot_lateral * rig_.hip_offset[0].x, 0, 0);
    }
    ankle.y = rig_.foot[side].ankle_height_m;
    return ankle + rig_.ball_offset[side];
  }

  FootTarget foot(float tau, int side) const {
    FootTarget f;
    if (idle()) {
      f.ball = footprint(0, side);
      return f;
    }
    const float u = tau / period_s_ - 0.5f * side;
    const int k = static_cast<int>(std::floor(u));
    const float psi = u - k;
    const FootShape& fs = rig_.foot[side];
    f.pitch = pitch_curve_(psi);
    if (psi < beta()) {
      f.ball = footprint(k, side);
      // Heel rocker: the ball's ground position is held (the heel takes the few mm of slip) so
      // the toe joint never slides once it is near the ground.
      f.ball.y = heel_contact_ball_height(f.pitch, side);
      f.toe_pitch = std::max(f.pitch, 0.0f);
      return f;
    }
    const float s = (psi - beta()) / (1.0f - beta());
    const glm::vec3 from = footprint(k, side);
    const glm::vec3 to = footprint(k + 1, side);
    // Walkers keep the foot back a little longer (warped progress) so the leg reaches the
    // footprint ahead; runners' feet accelerate harder after toe-off (smoothstep, not min-jerk).
    const float u_h = std::clamp((s - 0.03f) / 0.91f, 0.0f, 1.0f);
    const float h = running() ? smoothstep01(u_h) : minimum_jerk(std::pow(u_h, 1.1f));
    f.ball = from + (to - from) * h;
    f.ball.y = fs.ball_height_m + swing_curve_(s);
    // The toes leave the ground flat and realign with the foot during early swing.
    const float toe_bend = -pitch_curve_(beta()) * (1.0f - smoothstep01(s / 0.35f));
    f.toe_pitch = f.pitch + toe_bend;
    return f;
  }

  // Pelvis position (without the base height), yaw and roll at tau.
  void pelvis(float tau, glm::vec3* pos, float* yaw, float* roll) const {
    const float psi = wrap01(tau / period_s_);
    const float mid = 0.5f * beta();
    if (idle()) {
      *pos = glm::vec3(0.5f * p_.sway_m * std::sin(2 * kPi * psi),
                       0.5f * p_.bob_m * std::cos(4 * kPi * psi), 0.0f);
      *yaw = deg(p_.pelvis_yaw_deg) * std::sin(2 * kPi * psi + 1.0f);
      *roll = deg(p_.pelvis_roll_deg) * std::sin(2 * kPi * psi);
      return;
    }
    *pos = travel_ * (p_.speed_m_s * tau);
    // Walking: highs at mid-stance (vaulting over the stance leg); running: lows at mid-stance.
    // Side steps: one low per stride, in the wide double support.
    if (side_step()) {
      const float wide = 0.5f * (beta() - 0.5f);
      pos->y = -0.5f * p_.bob_m * std::cos(2 * kPi * (psi - wide));
    }
    // Lateral shift toward the stance leg (left = +x), one cycle per stride.
    if (!side_step()) pos->x += 0.5f * p_.sway_m * std::cos(2 * kPi * (psi - mid));
    *yaw = -deg(p_.pelvis_yaw_deg) * std::cos(2 * kPi * psi);  // left hip forward at left contact
    *roll = deg(p_.pelvis_roll_deg) * std::cos(2 * kPi * (psi - mid));  // swing side drops
  }

  void upper_body(float tau, PoseTargets* t) const {
    const float psi = wrap01(tau / period_s_);
    t->thorax_yaw = -0.7f * t->pelvis_yaw;
    t->lean = deg(p_.trunk_lean_deg);
    if (idle()) {
      t->lean += deg(1.2f) * std::sin(2 * kPi * 2.0f * psi);  // two breaths per clip
      t->head_yaw = deg(6.0f) * std::sin(2 * kPi * psi + 2.0f);
    }
    // Arms swing opposite to the same-side leg: the left arm is back at left heel contact.
    const float swing = deg(p_.arm_swing_deg) * std::cos(2 * kPi * (psi - p_.arm_back_phase));
    t->arm_forward[0] = deg(2.0f) - swing;
    t->arm_forward[1] = deg(2.0f) + swing;
    for (int s = 0; s < 2; ++s) {
      // The elbow bends a little more as the arm swings forward.
      t->elbow[s] = deg(p_.elbow_deg) + 0.35f * std::max(t->arm_forward[s], 0.0f);
    }
    // Relaxed arms hang close to the body: the upper arm just clears the trunk and the forearm
    // comes back in, so the hand passes beside the thigh (runners carry the elbows out a little
    // more and the hands toward the midline).
    t->arm_abduction = deg(running() ? 10.0f : 3.0f);
    t->forearm_abduction = deg(running() ? -15.0f : -6.0f);
  }

  // Root height that puts the hip at the leg's reach from the planned ankle with the knee flexed
  // by knee_rad.
  float leg_height(float tau, int side, float knee_rad) const {
    glm::vec3 root;
    float yaw, roll;
    pelvis(tau, &root, &yaw, &roll);
    root.y = 0.0f;
    const glm::vec3 hip = root + pelvis_rotation(yaw, roll) * rig_.hip_offset[side];
    const glm::vec3 ankle = ankle_from_ball(foot(tau, side), side);
    const float l1 = rig_.thigh_m[side], l2 = rig_.shank_m[side];
    const float chord2 = l1 * l1 + l2 * l2 + 2 * l1 * l2 * std::cos(knee_rad);
    const float h2 = (hip.x - ankle.x) * (hip.x - ankle.x) + (hip.z - ankle.z) * (hip.z - ankle.z);
    return ankle.y - hip.y + std::sqrt(std::max(chord2 - h2, 0.0f));
  }

  // Walking and running: the supporting leg sets the pelvis height through a knee-flexion profile
  // (loading response, mid-stance extension), so the vertical excursion and its two highs per
  // stride emerge from the leg geometry; running adds a ballistic flight. Tabulated per phase.
  void build_height_table() {
    const float b = beta();
    const float window = running() ? b : 0.5f;  // phase span over which one leg supports
    const float s = p_.loading_knee_deg;
    const MonotoneCurve knee(
        running() ? std::vector<std::pair<float, float>>{{0.0f, 20.0f}, {0.45f * b, s}, {b, 25.0f}}
                  : std::vector<std::pair<float, float>>{{0.0f, 4.0f},
                                                         {0.12f, s},
                                                         {0.3f, 6.0f},
                                                         {0.5f, 8.0f}},
        false);
    const int n = kTableSize, half = n / 2;
    std::vector<float> raw(n), limit(n, 1e9f);
    for (int side = 0; side < 2; ++side) {
      const float start = leg_height(0.5f * side * period_s_, side, 0.0f + deg(knee(0.0f)));
      const float end = leg_height((0.5f * side + window) * period_s_, side, deg(knee(window)));
      const float next = leg_height(0.5f * (1 - side) * period_s_ + (side ? period_s_ : 0.0f),
                                    1 - side, deg(knee(0.0f)));
      for (int i = 0; i < half; ++i) {
        const float local = 0.5f * i / half;
        const int index = side * half + i;
        const float tau = (0.5f * side + local) * period_s_;
        // The other foot, while still planted, must stay within reach too (double support).
        const float other_psi = wrap01(tau / period_s_ - 0.5f * (1 - side));
        if (other_psi < b) limit[index] = leg_height(tau, 1 - side, deg(3.0f));
        if (local <= window) {
          const float own = leg_height(tau, side, deg(knee(local)));
          limit[index] = std::min(limit[index], own);
          raw[index] = own;
          if (!running()) {
            // Both legs' windows must meet at the same height: tilt the curve toward the lower
            // end so it never exceeds the supporting leg's reach.
            const float u = local / window;
            raw[index] -= end >= start ? (end - start) * u : (start - end) * (1.0f - u);
          }
        } else {
          // Flight: a parabola under gravity from toe-off to the other foot's touchdown.
          const float flight_s = (0.5f - window) * period_s_;
          const float t = (local - window) * period_s_;
          const float v0 = (next - end + 0.5f * 9.81f * flight_s * flight_s) / flight_s;
          raw[index] = end + v0 * t - 0.5f * 9.81f * t * t;
        }
        raw[index] = std::min(raw[index], limit[index]);
      }
    }
    // Smooth the kinks at the hand-over between legs without exceeding any leg's reach: erode
    // (running minimum over the blur's whole support), then box-blur; every blurred sample is an
    // average of minima over windows that contain it, so it stays at or below the input.
    constexpr int kRadius = 4, kPasses = 3, kSupport = kRadius * kPasses;
    std::vector<float> smooth(n);
    for (int i = 0; i < n; ++i) {
      float lowest = raw[i];
      for (int k = -kSupport; k <= kSupport; ++k) lowest = std::min(lowest, raw[(i + k + n) % n]);
      smooth[i] = lowest;
    }
    for (int pass = 0; pass < kPasses; ++pass) {
      std::vector<float> tmp(n);
      for (int i = 0; i < n; ++i) {
        float sum = 0.0f;
        for (int k = -kRadius; k <= kRadius; ++k) sum += smooth[(i + k + n) % n];
        tmp[i] = sum / (2 * kRadius + 1);
      }
      smooth.swap(tmp);
    }
    height_table_ = std::move(smooth);
  }

  float table_height(float tau) const {
    const float x = wrap01(tau / period_s_) * kTableSize;
    const int i = static_cast<int>(x) % kTableSize;
    const float f = x - std::floor(x);
    return height_table_[i] * (1 - f) + height_table_[(i + 1) % kTableSize] * f;
  }

  // Idle and side steps: the highest pelvis that keeps every stance leg within max_leg_extension.
  float solve_pelvis_height() const {
    float best = 10.0f;
    const int samples = 240;
    for (int i = 0; i < samples; ++i) {
      const float tau = period_s_ * i / samples;
      glm::vec3 root;
      float yaw, roll;
      pelvis(tau, &root, &yaw, &roll);
      const glm::quat q = pelvis_rotation(yaw, roll);
      for (int s = 0; s < 2; ++s) {
        const float psi = wrap01(tau / period_s_ - 0.5f * s);
        if (!idle() && psi >= beta()) continue;
        const glm::vec3 hip = root + q * rig_.hip_offset[s];
        const glm::vec3 ankle = ankle_from_ball(foot(tau, s), s);
        const float reach = p_.max_leg_extension * (rig_.thigh_m[s] + rig_.shank_m[s]);
        const glm::vec2 horizontal(hip.x - ankle.x, hip.z - ankle.z);
        const float h2 = glm::dot(horizontal, horizontal);
        if (h2 >= reach * reach) continue;  // unreachable at any height; IK clamps it
        best = std::min(best, ankle.y - hip.y + std::sqrt(reach * reach - h2));
      }
    }
    return best;
  }

  const Skeleton& skel_;
  GaitParams p_;
  GaitRig rig_;
  float period_s_;
  MonotoneCurve pitch_curve_;
  MonotoneCurve swing_curve_;
  glm::vec3 travel_{0, 0, 1};
  float stride_m_ = 0.0f;
  float pelvis_height_ = 0.0f;
  static constexpr int kTableSize = 240;
  std::vector<float> height_table_;  // walking/running root height per phase sample [m]
};

}  // namespace
}  // namespace gait

Clip generate_gait_clip(const Skeleton& skeleton, const GaitParams& params, float fps) {
  const int stride_frames = frames_per_stride(params, fps);
  const float stride_s = stride_frames / fps;
  const int strides = params.kind == GaitKind::kIdle ? 1 : std::max(1, params.num_strides);
  Clip clip;
  clip.name = params.name;
  clip.source = "builtin";
  clip.fps = fps;
  clip.loops = true;
  clip.num_frames = stride_frames * strides;
  clip.num_joints = skeleton.num_joints();
  clip.rotations.resize(size_t(clip.num_frames) * clip.num_joints);
  clip.translations.resize(clip.rotations.size());
  GaitParams forward = params;
  if (params.mirror) forward.direction.x = -forward.direction.x;
  const gait::GaitPlanner planner(skeleton, forward, stride_s);
  for (int f = 0; f < clip.num_frames; ++f) {
    const float t = f / fps;
    const size_t offset = size_t(f) * clip.num_joints;
    const float tau = planner.time_origin() + (params.reverse_time ? -t : t);
    planner.evaluate(tau, clip.rotations.data() + offset, clip.translations.data() + offset);
  }
  if (params.mirror) gait::mirror_clip(skeleton, &clip);
  return clip;
}

}  // namespace gk
