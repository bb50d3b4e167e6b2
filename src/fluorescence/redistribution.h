#pragma once
// Redistribution weight w(λ', λ) between excitation λ' and emission λ
// (docs/physics.md §3). Kasha–Vavilov: w = 1 (photons conserved, emission shape
// independent of λ'). Stokes: only λ' < λ excites, renormalised by
// F(λ') = ∫_{λ>λ'} f(λ) dλ so Q still means photons out per photon in.
#include <vector>

#include "spectra/spectrum.h"

namespace chlorovdb {

enum class Redistribution { kasha_vavilov, stokes };

class RedistributionWeight {
 public:
  RedistributionWeight() = default;
  RedistributionWeight(Redistribution kind, const Spectrum& emission);

  Redistribution kind() const { return kind_; }
  float operator()(float lambda_excitation, float lambda_emission) const {
    if (kind_ == Redistribution::kasha_vavilov) return 1.f;
    if (lambda_excitation >= lambda_emission) return 0.f;
    const float F = emission_above(lambda_excitation);
    return F > 0.f ? 1.f / F : 0.f;
  }
  // F(λ') = ∫_{λ>λ'} f(λ) dλ (1 below the emission band, 0 above it).
  float emission_above(float lambda) const;

 private:
  Redistribution kind_ = Redistribution::kasha_vavilov;
  float lambda_min_ = 0, step_ = 1;
  std::vector<float> tail_;  // F on a 0.25 nm grid
};

}  // namespace chlorovdb
