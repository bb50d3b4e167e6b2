#pragma once
// Importance sampling of the excitation wavelength λ' for one (light, pigment)
// pair, with density proportional to  S_light(λ') · ε(λ') · λ'  (docs/physics.md §5.3):
// the light's photon flux times the pigment's absorption. The integral of that
// product, `total()`, also tells how strongly a light can excite a pigment: a
// light with total() == 0 never needs an excitation ray for that pigment.
//
// `ExcitationSampling::uniform` (scene key render.excitation_sampling, kept to
// measure what importance sampling buys) draws λ' uniformly over the same
// support instead: the span from the first to the last table bin where the
// product is positive. Same support, so both are unbiased for the same integral;
// sample() and pdf() then both follow the uniform density, so every estimator
// that combines several lights' densities uses the uniform one.
#include <vector>

#include "core/sampling.h"
#include "spectra/spectrum.h"

namespace chlorovdb {

enum class ExcitationSampling { importance, uniform };

class ExcitationSampler {
 public:
  ExcitationSampler() = default;
  // Tabulated on bins of `bin_nm` over [lambda_min, lambda_max].
  ExcitationSampler(const Spectrum& light, const Spectrum& epsilon,
                    ExcitationSampling mode = ExcitationSampling::importance, float lambda_min = kLambdaMinUV,
                    float lambda_max = kLambdaMax, float bin_nm = 0.5f);

  // ∫ S(λ') ε(λ') λ' dλ'  (units of S × L mol⁻¹ cm⁻¹ × nm²).
  float total() const { return total_; }
  bool can_excite() const { return total_ > 0.f; }

  // λ' and its pdf (per nm), by the sampler's mode. Requires can_excite().
  float sample(float u, float* pdf) const;
  float pdf(float lambda) const;

  ExcitationSampling mode() const { return mode_; }
  // [support_min, support_max): where the pdf is positive in uniform mode, and
  // the span of the bins the importance pdf is positive on.
  float support_min() const { return support_min_; }
  float support_max() const { return support_max_; }

 private:
  Distribution1D bins_;
  ExcitationSampling mode_ = ExcitationSampling::importance;
  float lambda_min_ = 0, bin_nm_ = 1;
  float total_ = 0;
  float support_min_ = 0, support_max_ = 0, uniform_pdf_ = 0;
};

// λ' for one light's excitation: its sampler's density (∝ S·ε·λ', or uniform
// over that band with render.excitation_sampling = uniform); a light that cannot
// excite the pigment (kept only when skips are off, to measure them) draws λ'
// uniformly over the whole range. *pdf per nm.
float sample_excitation(const ExcitationSampler& es, float u, float* pdf);
float excitation_pdf(const ExcitationSampler& es, float lambda);

}  // namespace chlorovdb
