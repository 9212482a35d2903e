#pragma once
// Small order statistics shared by clip analysis, the library and the metrics.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

namespace gk {

// Percentile q in [0, 1] of v: the sample at index floor(q * n) of v sorted (q = 0.5 is the upper
// median of an even count); 0 for no samples. Takes v by value: nth_element reorders it.
inline float percentile(std::vector<float> v, double q) {
  if (v.empty()) return 0.0f;
  const size_t k = std::min(
      v.size() - 1, static_cast<size_t>(std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

// The standard deviation per axis of white noise on 2-D positions sampled at even steps, from the
// lengths of their second differences p[i+1] - 2 p[i] + p[i-1]: each axis of one has a variance
// of 6 sigma^2, and the median length of such a 2-D Gaussian is 1.1774 (sqrt(2 ln 2)) times its
// per-axis deviation. A median, so a minority of real accelerations does not count. 0 for none.
inline float sigma_from_second_differences(std::vector<float> lengths) {
  return lengths.empty() ? 0.0f : percentile(std::move(lengths), 0.5) / (1.1774f * std::sqrt(6.0f));
}

}  // namespace gk
