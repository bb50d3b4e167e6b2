#pragma once
// Importance density for camera wavelengths (pbrt-v4's SampleVisibleWavelengths):
// p(lambda) ∝ 1 / cosh²(0.0072 (lambda − 538)), which follows the eye's
// sensitivity, normalised exactly over [kLambdaMin, kLambdaMax] (360–830 nm).
// SampledWavelengths::sample_visible draws its lanes from it.

namespace chlorovdb {

// Density in 1/nm; zero outside [kLambdaMin, kLambdaMax].
float visible_wavelength_pdf(float lambda_nm);
// Inverse CDF: u in [0, 1) -> lambda in nm.
float sample_visible_wavelength(float u);

}  // namespace chlorovdb
