#pragma once
// Importance density for camera wavelengths (pbrt-v4's SampleVisibleWavelengths):
// p(lambda) ∝ 1 / cosh²(0.0072 (lambda − 538)), which follows the eye's
// sensitivity, normalised exactly over [kLambdaMin, kLambdaMax] (360–830 nm).
// SampledWavelengths::sample_visible draws its lanes from it.
//
// WavelengthDistribution: the density a scene's camera wavelengths are drawn from.
// The eye's importance does not know a scene's sources. A mercury lamp puts a large
// share of its visible power into 1 nm lines (436, 546, 578 nm): lanes drawn by the
// eye's density land on a line rarely and then carry its whole energy, one firefly
// per hit. `mixture` draws λ from a weighted sum
// of densities instead (the eye's, the lights' spectra, the pigments' re-emission),
// tabulated as a piecewise-constant density over [kLambdaMin, kLambdaMax]; lanes stay
// stratified, in the mixture's CDF, and each lane carries its own pdf, which the film
// divides by, so the image's expectation does not depend on the mixture.
#include <functional>
#include <vector>

#include "core/sampling.h"
#include "spectra/sampled.h"

namespace chlorovdb {

// Density in 1/nm; zero outside [kLambdaMin, kLambdaMax].
float visible_wavelength_pdf(float lambda_nm);
// Inverse CDF: u in [0, 1) -> lambda in nm.
float sample_visible_wavelength(float u);

class WavelengthDistribution {
 public:
  // A mixture component: a non-negative function of λ (any normalisation) and its
  // share of the mixture. A component that is zero over the camera range is left
  // out, and the shares of the others are renormalised.
  struct Component {
    std::function<double(float lambda_nm)> shape;
    double share = 0;
  };
  // Bin width of the tabulated density, nm: a line of a 1 nm table spans 4 bins.
  static constexpr float kBinWidth = 0.5f;

  // The eye's importance alone, drawn in closed form (SampledWavelengths::sample_visible).
  static WavelengthDistribution visible() { return {}; }
  // Throws std::invalid_argument if a share is negative or not finite, a shape is
  // negative or not finite somewhere, or no component has weight.
  static WavelengthDistribution mixture(const std::vector<Component>& components);

  bool is_visible() const { return bins_.empty(); }
  // Density in 1/nm; zero outside [kLambdaMin, kLambdaMax].
  float pdf(float lambda_nm) const;
  // `count` stratified lanes: lane i inverts the CDF at frac(u + i / count).
  SampledWavelengths sample(float u, int count) const;

 private:
  Distribution1D bins_;  // probability of each kBinWidth bin; empty for the eye's importance
};

}  // namespace chlorovdb
