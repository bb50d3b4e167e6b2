#pragma once
// Rayleigh phase function (molecular scattering): p(cos theta) = 3/(16 pi) (1 + cos^2 theta),
// sampled exactly by inverting its CDF in closed form.
#include <cmath>

#include "core/constants.h"

namespace chlorovdb {

inline float rayleigh_phase(float cos_theta) { return 3.f / (16.f * kPi) * (1.f + cos_theta * cos_theta); }

// cos theta distributed as the Rayleigh phase function, from u in [0, 1).
//
// Density of mu = cos theta: 2 pi p(mu) = 3/8 (1 + mu^2) on [-1, 1], so the CDF is
//   F(mu) = 3/8 (mu + mu^3/3 + 4/3) = (mu^3 + 3 mu + 4) / 8.
// F(mu) = u is the depressed cubic mu^3 + 3 mu - 2z = 0 with z = 4u - 2 in [-2, 2].
// Its discriminant (q/2)^2 + (p/3)^3 = z^2 + 1 is positive, so Cardano gives the one real root
//   mu = cbrt(z + sqrt(z^2 + 1)) + cbrt(z - sqrt(z^2 + 1)).
// The two radicands multiply to -1, so with A = cbrt(z + sqrt(z^2 + 1)) the root is mu = A - 1/A
// (check: u = 1, z = 2, A = cbrt(2 + sqrt 5) = golden ratio, mu = 1). The root is odd in z;
// evaluating it at |z| avoids the cancellation in z + sqrt(z^2 + 1) for negative z.
inline float sample_rayleigh_cos_theta(float u) {
  const float z = 4.f * u - 2.f;
  const float a = std::cbrt(std::fabs(z) + std::sqrt(z * z + 1.f));
  const float mu = std::copysign(a - 1.f / a, z);
  return std::fmax(-1.f, std::fmin(1.f, mu));
}

}  // namespace chlorovdb
