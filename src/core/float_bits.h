#pragma once
// The neighbouring floats of a value, by its bit pattern (pbrt-v4's NextFloatUp /
// NextFloatDown): std::nextafter is an out-of-line libm call, and these run for
// every ray spawned off a surface. Same results as std::nextafter toward +-infinity,
// -0 and +0 both stepping to the smallest denormal.
#include <bit>
#include <cmath>
#include <cstdint>

namespace chlorovdb {

inline float next_float_up(float v) {
  if (std::isinf(v) && v > 0.f) return v;
  if (v == 0.f) v = 0.f;  // -0 -> +0
  const uint32_t bits = std::bit_cast<uint32_t>(v);
  return std::bit_cast<float>(v >= 0.f ? bits + 1 : bits - 1);
}

inline float next_float_down(float v) {
  if (std::isinf(v) && v < 0.f) return v;
  if (v == 0.f) v = -0.f;  // +0 -> -0
  const uint32_t bits = std::bit_cast<uint32_t>(v);
  return std::bit_cast<float>(v > 0.f ? bits - 1 : bits + 1);
}

}  // namespace chlorovdb
