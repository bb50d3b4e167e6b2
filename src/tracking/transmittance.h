#pragma once
// Transmittance along a ray segment through one medium, by a choice of
// unbiased estimators (selectable in the scene and on the command line).
//
// Every estimator returns, for each carried wavelength, an unbiased estimate of
// T(lambda) = exp(-integral sigma_t(x, lambda) dx) given these wavelengths (no
// reliance on averaging over hero choices). Tentative collisions are drawn at,
// per majorant segment, the largest majorant over the carried lanes, so that
// the same collisions serve every lane with factors in [0, 1]:
//   ratio           T = prod_i (1 - sigma_t(x_i) / sigma_bar)                  (Novak et al. 2014)
//   residual_ratio  T = exp(-sigma_c dt) prod_i (1 - (sigma_t(x_i) - sigma_c) / sigma_bar_r),
//                   sigma_c the segment's control (minimum) coefficient, sigma_bar_r the residual
//                   majorant; exact where the medium is uniform, so its variance stays low in thick media
//   delta           track-length estimator: each tentative collision is real with probability
//                   1 - P, P = max over lanes of (1 - sigma_t / sigma_bar); a real collision returns 0,
//                   a null one weights each lane by its own (1 - sigma_t / sigma_bar) / P. With one
//                   wavelength (excitation rays) this is the classic 0/1 free-path test. A decision by
//                   the hero lane alone would bias lanes that are more transparent than the hero.
//   closed_form     exp(-sigma_t L), homogeneous media only; a grid medium has no closed form and
//                   runs residual_ratio instead.
// An unbounded ray (t_max >= kInfinity) ends outside every grid, where the medium is uniform:
// there T is exactly 0, or 1 on lanes whose sigma_t is 0.
#include <optional>
#include <string_view>

#include "core/rng.h"
#include "media/medium.h"
#include "spectra/sampled.h"

namespace chlorovdb {

enum class TransmittanceEstimator { delta, ratio, residual_ratio, closed_form };

// "delta", "ratio", "residual_ratio", "closed_form"; nullopt for anything else ("auto" is the caller's choice).
std::optional<TransmittanceEstimator> transmittance_estimator_from_string(std::string_view name);
const char* to_string(TransmittanceEstimator estimator);
// What "auto" picks: closed form where homogeneous, residual ratio tracking in grids.
inline TransmittanceEstimator automatic_transmittance_estimator(const Medium& medium) {
  return medium.homogeneous() ? TransmittanceEstimator::closed_form : TransmittanceEstimator::residual_ratio;
}

// T over [0, t_max] of `ray` (its own parameter; the direction need not be unit length).
SampledSpectrum transmittance(const Ray& ray, float t_max, const SampledWavelengths& lambda, const Medium& medium,
                              const PreparedMedium& prepared, TransmittanceEstimator estimator, Rng& rng);

}  // namespace chlorovdb
