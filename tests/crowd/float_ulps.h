#pragma once
// Distances between floats in units in the last place, for the SIMD maths tests.

#include <cstdint>
#include <cstdlib>
#include <cstring>

namespace gk::test {

// Floats as integers in the order of the reals, so that ulps are a difference.
inline int64_t ordered(float f) {
  int32_t i;
  std::memcpy(&i, &f, sizeof i);
  return i < 0 ? -int64_t(i & 0x7fffffff) : int64_t(i);
}
inline int64_t ulps(float a, float b) { return std::llabs(ordered(a) - ordered(b)); }
inline float from_bits(uint32_t b) {
  float f;
  std::memcpy(&f, &b, sizeof f);
  return f;
}

}  // namespace gk::test
