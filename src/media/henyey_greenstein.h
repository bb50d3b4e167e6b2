#pragma once
// Henyey-Greenstein phase function (particle scattering), pbrt-v4 convention:
// cos_theta is the cosine between wo and wi, both pointing away from the
// scattering point, so forward scattering (g > 0) peaks at cos_theta = -1.
#include <algorithm>
#include <cmath>

#include "core/constants.h"

namespace chlorovdb {

inline float henyey_greenstein(float cos_theta, float g) {
  const float denom = 1.f + g * g + 2.f * g * cos_theta;
  return kInv4Pi * (1.f - g * g) / (denom * std::sqrt(std::max(denom, 0.f)));
}

// cos theta (between wo and the sampled wi) from u in [0, 1). Inverting the CDF of
// the textbook form p(mu') ~ (1 - g^2) / (1 + g^2 - 2 g mu')^(3/2) (mu' = -cos theta) gives
//   mu' = (1 + g^2 - ((1 - g^2) / (1 - g + 2 g xi))^2) / (2 g);
// with xi = 1 - u that is cos theta below. Near g = 0 that expression divides 0 by 0,
// while the distribution is uniform: sample it as such.
inline float sample_henyey_greenstein_cos_theta(float u, float g) {
  if (std::fabs(g) < 1e-3f) return 1.f - 2.f * u;
  const float s = (1.f - g * g) / (1.f + g - 2.f * g * u);
  return std::clamp(-1.f / (2.f * g) * (1.f + g * g - s * s), -1.f, 1.f);
}

}  // namespace chlorovdb
