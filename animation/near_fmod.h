#pragma once
// std::fmod for the values the per-frame code mostly wraps: a phase, an angle or a frame a step
// past its period. The libm call was about 2% of the mediator's instructions (every unwrapped
// torso angle, every gait phase step).

#include <cmath>

namespace gk {

// std::fmod(x, y) for y > 0, the same bits, without the call where x lies in (-y, 2y): fmod
// returns x as it is within (-y, y), and in [y, 2y) its result x - y, which the subtraction gives
// exactly (Sterbenz: y / 2 <= x <= 2y). Elsewhere (NaN too) it is fmod's.
inline float near_fmod(float x, float y) {
  if (x > -y && x < y) return x;
  if (x >= y && x < 2.0f * y) return x - y;
  return std::fmod(x, y);
}

}  // namespace gk
