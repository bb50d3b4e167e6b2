#include "core/exponential.h"

#include <cmath>

namespace chlorovdb {
namespace {

// Marsaglia and Tsang's table set-up for 256 layers, with 24-bit positions.
ExponentialZiggurat make_ziggurat() {
  constexpr double kScale = 16777216.0;       // 2^24 positions per layer
  constexpr double kArea = 3.949659822581572e-3;  // area of every layer (the base one includes the tail)
  ExponentialZiggurat z{};
  double x = ExponentialZiggurat::kTailStart, x_outer = x;
  const double q = kArea / std::exp(-x);  // the base layer as a rectangle of height e^{-x_255}
  z.k[0] = uint32_t(x / q * kScale);
  z.k[1] = 0;
  z.w[0] = float(q / kScale);
  z.w[255] = float(x / kScale);
  z.f[0] = 1.f;
  z.f[255] = float(std::exp(-x));
  for (int i = 254; i >= 1; --i) {
    x = -std::log(kArea / x + std::exp(-x));
    z.k[i + 1] = uint32_t(x / x_outer * kScale);
    x_outer = x;
    z.f[i] = float(std::exp(-x));
    z.w[i] = float(x / kScale);
  }
  return z;
}

}  // namespace

const ExponentialZiggurat kExponentialZiggurat = make_ziggurat();

float sample_standard_exponential_slow(uint32_t r, Rng& rng) {
  const ExponentialZiggurat& z = kExponentialZiggurat;
  for (;;) {
    const uint32_t i = r & 0xffu, j = r >> 8;
    if (j < z.k[i]) return float(j) * z.w[i];
    // The tail beyond x_255 is again exponential (memoryless): shift a fresh sample.
    if (i == 0) return float(ExponentialZiggurat::kTailStart - std::log(1.0 - double(rng.uniform())));
    // A wedge: accept under e^{-x} between the layer's two edges.
    const float x = float(j) * z.w[i];
    if (z.f[i] + rng.uniform() * (z.f[i - 1] - z.f[i]) < std::exp(-x)) return x;
    r = rng.next_u32();
  }
}

}  // namespace chlorovdb
