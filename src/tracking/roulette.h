#pragma once
// The one Russian-roulette policy of every transmittance-like weight a ray
// tracks toward a light (ratio and residual ratio tracking, the MIS-ratio
// tracking of light connections): a weight window. Once the weight is below
// kRouletteWeight on every lane, the ray continues with probability
// q = weight / kRouletteWeight and survivors carry kRouletteWeight. Higher
// windows stop rays sooner but add variance: on the cloud (docs/performance.md),
// 0.5 saves 1.5 % / 3.5 % of the instructions at tau~10 / tau~100 for 1.8 % /
// 2.5 % more MSE, a wash; 1.0 loses 11 % / 4 % efficiency.
#include <algorithm>

namespace chlorovdb {

inline constexpr float kRouletteWeight = 0.25f;
// The least survival probability played. Rng::uniform() has 24 bits, so a q below about
// 2^-24 would not be the probability actually played (u = 0 alone passes, with
// probability 2^-24), and its survivors' 1/q could overflow to infinity (a predicted
// roulette's q reaches 1e-40 at tau ~ 85). Clamped, survival stays exactly q to within
// 2^-12 and a survivor's factor grows at most 4096-fold.
inline constexpr float kMinSurvival = 1.f / 4096.f;

// The survival probability for a weight whose largest lane is `weight_max`: 1 (no
// roulette) at or above the window.
inline float roulette_survival(float weight_max) {
  return weight_max < kRouletteWeight ? std::max(weight_max / kRouletteWeight, kMinSurvival) : 1.f;
}

}  // namespace chlorovdb
