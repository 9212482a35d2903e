#pragma once
// Small curve helpers for the procedural gait generator (internal to animation/).

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace gk::gait {

inline constexpr float kPi = 3.14159265358979f;
inline float deg(float degrees) { return degrees * kPi / 180.0f; }
inline float wrap01(float x) { return x - std::floor(x); }
inline float smoothstep01(float u) {
  u = std::clamp(u, 0.0f, 1.0f);
  return u * u * (3.0f - 2.0f * u);
}
// Minimum-jerk progress: zero velocity and acceleration at both ends, so a swing foot leaves and
// reaches its footprint without a horizontal jolt.
inline float minimum_jerk(float u) {
  u = std::clamp(u, 0.0f, 1.0f);
  return u * u * u * (10.0f + u * (-15.0f + 6.0f * u));
}

// Monotone cubic Hermite interpolation (Fritsch-Carlson) through keys (x, y): no overshoot, so a
// foot that is flat between two keys stays exactly flat. Periodic over [0, 1) or clamped to the
// first/last key with zero end slopes.
class MonotoneCurve {
 public:
  MonotoneCurve(std::vector<std::pair<float, float>> keys, bool periodic) : periodic_(periodic) {
    std::sort(keys.begin(), keys.end());
    if (periodic_) {
      // Pad one key on each side so interior slopes cover the wrap.
      const auto first = keys.front();
      const auto last = keys.back();
      keys.insert(keys.begin(), {last.first - 1.0f, last.second});
      keys.push_back({first.first + 1.0f, first.second});
    }
    keys_ = std::move(keys);
    const size_t n = keys_.size();
    slopes_.assign(n, 0.0f);
    for (size_t i = 1; i + 1 < n; ++i) {
      const float d0 = secant(i - 1);
      const float d1 = secant(i);
      if (d0 * d1 <= 0.0f) continue;  // local extremum or flat side: zero slope keeps it monotone
      // Weighted harmonic mean of the neighbouring secants (Fritsch-Butland).
      const float h0 = keys_[i].first - keys_[i - 1].first;
      const float h1 = keys_[i + 1].first - keys_[i].first;
      const float w0 = 2.0f * h1 + h0;
      const float w1 = h1 + 2.0f * h0;
      slopes_[i] = (w0 + w1) / (w0 / d0 + w1 / d1);
    }
  }

  float operator()(float x) const {
    if (periodic_) x = wrap01(x);
    if (x <= keys_.front().first) return keys_.front().second;
    if (x >= keys_.back().first) return keys_.back().second;
    size_t i = 0;
    while (keys_[i + 1].first < x) ++i;
    const float h = keys_[i + 1].first - keys_[i].first;
    const float t = (x - keys_[i].first) / h;
    const float t2 = t * t;
    const float t3 = t2 * t;
    return (2 * t3 - 3 * t2 + 1) * keys_[i].second + (t3 - 2 * t2 + t) * h * slopes_[i] +
           (-2 * t3 + 3 * t2) * keys_[i + 1].second + (t3 - t2) * h * slopes_[i + 1];
  }

 private:
  float secant(size_t i) const {
    return (keys_[i + 1].second - keys_[i].second) / (keys_[i + 1].first - keys_[i].first);
  }
  bool periodic_;
  std::vector<std::pair<float, float>> keys_;
  std::vector<float> slopes_;
};

}  // namespace gk::gait
