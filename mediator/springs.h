#pragma once
// Critically damped springs (exact integration, stable for any dt): the simulator's velocity and
// torso orientation are filtered through them so zig-zag never reaches the body.

#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/vec2.hpp>

#include "animation/near_fmod.h"

namespace gk {

// Damping of a critically damped spring that halves its error every halflife_s seconds.
inline float halflife_to_damping(float halflife_s) {
  return (4.0f * std::numbers::ln2_v<float>) / (halflife_s + 1e-5f);
}

// A spring's half damping y and its decay exp(-y dt) over a step of dt [s]: the same for every
// agent stepped by the same dt and halflife, so a whole-crowd pass takes its exp once per frame.
struct SpringStep {
  float y = 0.0f;
  float eydt = 1.0f;
  float dt = 0.0f;
};
inline SpringStep spring_step(float halflife_s, float dt) {
  const float y = halflife_to_damping(halflife_s) * 0.5f;
  return {y, std::exp(-y * dt), dt};
}

template <typename T>
inline void critical_spring(T& x, T& v, const T& goal, const SpringStep& s) {
  const T j0 = x - goal;
  const T j1 = v + j0 * s.y;
  x = s.eydt * (j0 + j1 * s.dt) + goal;
  v = s.eydt * (v - j1 * s.y * s.dt);
}

template <typename T>
inline void critical_spring(T& x, T& v, const T& goal, float halflife_s, float dt) {
  critical_spring(x, v, goal, spring_step(halflife_s, dt));
}

// 0 -> 1 with zero slope at both ends (x clamped to [0, 1]).
inline float smoothstep01(float x) {
  x = x < 0.0f ? 0.0f : (x > 1.0f ? 1.0f : x);
  return x * x * (3.0f - 2.0f * x);
}

// Length of (x, z), as std::hypot(x, z) gives it for finite x and z, without the libm call:
// glibc's hypotf squares in double (a finite float's square cannot overflow it), takes the root
// and rounds once, and so does this (the same bits). Only infinities with NaN differ (hypot's
// infinity, here NaN), and callers compare either against finite limits alike.
inline float ground_length(float x, float z) {
  const double dx = x, dz = z;
  return static_cast<float>(std::sqrt(dx * dx + dz * dz));
}

inline float wrap_pi(float a) {
  constexpr float kPi = std::numbers::pi_v<float>;
  a += kPi;
  // fmod returns an x already in [0, y) as it is: skip the call (same bits).
  if (!(a >= 0.0f && a < 2.0f * kPi)) {
    a = near_fmod(a, 2.0f * kPi);
    if (a < 0.0f) a += 2.0f * kPi;
  }
  return a - kPi;
}

// Moves a toward b by at most max_step.
inline float approach(float a, float b, float max_step) {
  return a + std::clamp(b - a, -max_step, max_step);
}

// Turns `angle` [rad] toward `target` (the shortest way round) over dt [s] at a turn `rate`
// [rad/s] that changes by at most accel * dt per step and never exceeds max_rate: it speeds up,
// and slows down so as to stop on the target, from the rate at which braking step by step covers
// what is left (v dt + (v - a dt) dt + ... = v^2 / 2a + v dt / 2 = |error|); once within that last
// step it lands on the target at rest. A target that is not a number turns nothing (angle and
// rate are carried state). A huge accel turns at max_rate and stops at once.
inline void turn_toward(float& angle, float& rate, float target, float max_rate, float accel,
                        float dt) {
  if (!std::isfinite(target)) target = angle;
  const float err = wrap_pi(target - angle);
  const float half = 0.5f * accel * dt;
  const float stop = std::sqrt(half * half + 2.0f * accel * std::abs(err)) - half;
  rate = approach(rate, std::copysign(std::min(max_rate, stop), err), accel * dt);
  if (std::abs(err) <= std::abs(rate) * dt && err * rate >= 0.0f && std::abs(rate) <= accel * dt) {
    angle = target;
    rate = 0.0f;
  } else {
    angle = wrap_pi(angle + rate * dt);
  }
}

}  // namespace gk
