#pragma once
// The foot's pitch about its toe for leg IK (mediator/pose_synthesis.cc): how far a heel may
// rise, when a foot stands on its heel, and the heel-off pivot that lets a leg reach its pinned
// ball. Inline: lock_feet calls them for every leg of every agent.

#include <algorithm>
#include <cmath>

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

namespace gk::heel_pivot {

// A raised heel puts the toe -> ankle line at most this steep [rad] (about 57 deg, a stance
// foot's plantarflexion at toe-off): the pivot never turns a foot past standing on its tip.
constexpr float kMaxHeelOff = 1.0f;
constexpr float kPi = 3.14159265358979f;

// How much more the foot may pitch up from its elevation (toe -> ankle vector d) [rad].
inline float heel_room(const glm::vec3& d) {
  const float len = glm::length(d);
  if (len < 1e-6f) return 0.0f;
  return std::max(0.0f, kMaxHeelOff - std::asin(std::clamp(d.y / len, -1.0f, 1.0f)));
}

// The toe -> ankle vector d with the heel as high as it rises (pitched up about the toe by
// heel_room(d)); d itself for a foot standing straight up.
inline glm::vec3 fully_raised(const glm::vec3& d) {
  const glm::vec3 across = glm::cross(d, glm::vec3(0.0f, 1.0f, 0.0f));
  if (glm::length(across) <= 1e-6f) return d;
  return glm::angleAxis(heel_room(d), glm::normalize(across)) * d;
}

// A foot whose ball is this much higher [rad of pitch] over its floor than its ankle is over its
// own stands on its heel, rolling down onto the ball (a heel strike lands some 15-25 deg toe-up);
// a flat foot, captured or not, is within a few degrees of 0.
inline const float kOnHeelSin = std::sin(10.0f * kPi / 180.0f);

// True when a foot with its ankle and ball (toe) here stands on its heel: pitched toe-up by more
// than kOnHeelSin against the pose the library plants it in (its floor heights).
inline bool on_heel(const glm::vec3& ankle, const glm::vec3& toe, float ankle_floor,
                    float toe_floor) {
  const float rise = (toe.y - toe_floor) - (ankle.y - ankle_floor);
  return rise > kOnHeelSin * glm::length(toe - ankle);
}

// The foot's pitch about its toe [rad] that lifts an ankle at toe + d to ankle_floor (0 when it is
// already as high): the heel rises, the ball stays.
inline float heel_to_floor(const glm::vec3& toe, const glm::vec3& d, float ankle_floor) {
  const float len = glm::length(d);
  if (len < 1e-6f || toe.y + d.y >= ankle_floor) return 0.0f;
  const float now = std::asin(std::clamp(d.y / len, -1.0f, 1.0f));
  const float want = std::asin(std::clamp((ankle_floor - toe.y) / len, -1.0f, 1.0f));
  // heel_room(d), its length and asin those above.
  return std::clamp(want - now, 0.0f, std::max(0.0f, kMaxHeelOff - now));
}

// The foot's pitch about its toe that brings the ankle within `limit` of the hip: the heel rises
// about the ball, as far as heel_room allows (bisection; the distance shrinks as the heel rises
// toward the hip). Returns the pitch [rad]. `closed_form` off: every step measures the distance
// (the reference the closed form is tested against).
inline float heel_off_pivot(const glm::vec3& toe, const glm::vec3& ankle, const glm::vec3& hip,
                            float limit, bool closed_form = true) {
  const glm::vec3 d = ankle - toe;
  const glm::vec3 axis = glm::normalize(glm::cross(d, glm::vec3(0, 1, 0)));
  const float room = heel_room(d);
  auto dist = [&](float a) { return glm::length(toe + glm::angleAxis(a, axis) * d - hip); };
  if (dist(room) > limit) return room;
  // Each step asks whether dist(mid) > limit. The axis is square to d, so the squared distance
  // is K + A cos a + B sin a = K + M cos(a - phi): it exceeds limit^2 where |a - phi| (wrapped)
  // is below acos((limit^2 - K) / M). Far from that boundary the answer is certain without the
  // rotation; within kSure of it, and near a tangency where the boundary is ill-conditioned,
  // the step measures dist as before, so the steps, and the pitch, are the same.
  constexpr float kSure = 1e-3f;  // [rad], against an analytic error of about 1e-5 rad
  const glm::vec3 e = toe - hip;
  const glm::vec3 w = glm::cross(axis, d);
  const float k = glm::dot(e, e) + glm::dot(d, d);
  const float a_cos = 2.0f * glm::dot(e, d), b_sin = 2.0f * glm::dot(e, w);
  const float m = std::sqrt(a_cos * a_cos + b_sin * b_sin);
  const float c = m > 1e-6f ? (limit * limit - k) / m : 2.0f;
  const bool analytic = closed_form && std::abs(c) < 1.0f - 1e-3f;
  const float phi = analytic ? std::atan2(b_sin, a_cos) : 0.0f;
  const float half_width = analytic ? std::acos(c) : 0.0f;
  auto beyond = [&](float a) {
    if (analytic) {
      float delta = a - phi;
      if (delta > kPi) delta -= 2.0f * kPi;
      if (delta < -kPi) delta += 2.0f * kPi;
      const float margin = half_width - std::abs(delta);
      if (std::abs(margin) > kSure) return margin > 0.0f;
    }
    return dist(a) > limit;
  };
  float lo = 0.0f, hi = room;
  for (int i = 0; i < 12; ++i) {
    const float mid = 0.5f * (lo + hi);
    (beyond(mid) ? lo : hi) = mid;
  }
  return hi;
}

}  // namespace gk::heel_pivot
