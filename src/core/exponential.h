#pragma once
// Standard exponential variates (rate 1) by the ziggurat method (Marsaglia and
// Tsang 2000, "The ziggurat method for generating random variables", REXP):
// 256 layers of equal area under e^{-x}; a sample falls inside its layer's
// rectangle 98.9 % of the time and costs one 32-bit draw, two table loads and a
// multiply, no log. Free flights in thick media are mostly null collisions, and
// each needs a fresh exponential: this replaced -log(1 - u) there
// (docs/performance.md). The distribution is exact: the rare wedge and tail
// cases fall back to rejection and to the memoryless tail.
#include <array>
#include <cstdint>

#include "core/rng.h"

namespace chlorovdb {

struct ExponentialZiggurat {
  static constexpr int kLayers = 256;
  // A draw r splits into layer i = r & 255 and position j = r >> 8 (24 bits).
  std::array<uint32_t, kLayers> k;  // j < k[i]: inside layer i's rectangle, accept j * w[i]
  std::array<float, kLayers> w;     // position scale of layer i
  std::array<float, kLayers> f;     // e^{-x_i} at layer i's outer edge x_i
  static constexpr double kTailStart = 7.697117470131487;  // x_255: the base layer's tail starts here
};
extern const ExponentialZiggurat kExponentialZiggurat;

// The rare cases of sample_standard_exponential (wedges and tail), out of line.
float sample_standard_exponential_slow(uint32_t r, Rng& rng);

// A sample of p(x) = e^{-x}, x >= 0.
inline float sample_standard_exponential(Rng& rng) {
  const uint32_t r = rng.next_u32();
  const uint32_t i = r & 0xffu, j = r >> 8;
  if (j < kExponentialZiggurat.k[i]) return float(j) * kExponentialZiggurat.w[i];
  return sample_standard_exponential_slow(r, rng);
}

}  // namespace chlorovdb
