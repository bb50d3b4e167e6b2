#pragma once
// Importance sampling of the excitation wavelength λ' for one (light, pigment)
// pair, with density proportional to  S_light(λ') · ε(λ') · λ'  (PHYSICS.md §5.3):
// the light's photon flux times the pigment's absorption. The integral of that
// product, `total()`, also tells how strongly a light can excite a pigment: a
// light with total() == 0 never needs an excitation ray for that pigment.
#include <vector>

#include "core/sampling.h"
#include "spectra/spectrum.h"

namespace chlorovdb {

class ExcitationSampler {
 public:
  ExcitationSampler() = default;
  // Tabulated on bins of `bin_nm` over [lambda_min, lambda_max].
  ExcitationSampler(const Spectrum& light, const Spectrum& epsilon, float lambda_min = kLambdaMinUV,
                    float lambda_max = kLambdaMax, float bin_nm = 0.5f);

  // ∫ S(λ') ε(λ') λ' dλ'  (units of S × L mol⁻¹ cm⁻¹ × nm²).
  float total() const { return total_; }
  bool can_excite() const { return total_ > 0.f; }

  // λ' and its pdf (per nm). Requires can_excite().
  float sample(float u, float* pdf) const;
  float pdf(float lambda) const;

 private:
  Distribution1D bins_;
  float lambda_min_ = 0, bin_nm_ = 1;
  float total_ = 0;
};

}  // namespace chlorovdb
