#pragma once
// Small order statistics shared by clip analysis, the library and the metrics.

#include <algorithm>
#include <cmath>
#include <cstddef>
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

}  // namespace gk
