#pragma once
// From spectral radiance to colour: CIE 1931 2° XYZ (spectra/cie1931_2deg_xyz.csv,
// 360–830 nm), then linear sRGB or ACEScg.
//
// Normalisation: XYZ = ∫ cmf(λ) L(λ) dλ / ∫ ȳ(λ) dλ, so a constant spectrum of 1
// has Y = 1 (pbrt-v4's convention) and Y is in the units of L.
#include <array>

#include "spectra/sampled.h"
#include "spectra/spectrum.h"

namespace chlorovdb {

struct XYZ {
  double x = 0, y = 0, z = 0;
};
struct RGB {
  double r = 0, g = 0, b = 0;
};

// CIE xy chromaticities of an RGB space's primaries and white point.
struct Chromaticities {
  double red_x, red_y, green_x, green_y, blue_x, blue_y, white_x, white_y;
};
// IEC 61966-2-1 sRGB (Rec. 709 primaries, D65 white).
inline constexpr Chromaticities kSrgbChromaticities{0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290};
// ACEScg (SMPTE ST 2065-1 / Academy S-2014-004: AP1 primaries, ACES white ≈ D60).
inline constexpr Chromaticities kAcesCgChromaticities{0.713, 0.293, 0.165, 0.830, 0.128, 0.044, 0.32168, 0.33767};

// The colour-matching functions at one wavelength (zero outside 360–830 nm), and ∫ȳ dλ in nm.
XYZ cie_cmf(float lambda_nm);
double cie_y_integral();

// Monte Carlo estimate from one path: the mean over lambda.count() lanes of
// cmf(λ_i) L_i / pdf_i, divided by ∫ȳ. Lanes with pdf 0 (terminated) contribute 0.
XYZ to_xyz(const SampledSpectrum& L, const SampledWavelengths& lambda);
// The same sum split in two: per-lane factors cmf(λ_i) / (pdf_i · count · ∫ȳ), computed
// once per sample, then one dot product per spectrum (the film's layers share them).
struct XyzLaneWeights {
  std::array<double, kMaxWavelengths> x{}, y{}, z{};
};
XyzLaneWeights xyz_lane_weights(const SampledWavelengths& lambda);
XYZ to_xyz(const SampledSpectrum& L, const XyzLaneWeights& w);
// The integral itself, exact for tabulated and constant spectra (Simpson's rule
// between the knots of both tables, where the integrand is quadratic).
XYZ spectrum_to_xyz(const Spectrum& s);
// Y of spectrum_to_xyz: the photometric weight of a light. pbrt-v4 divides a light's
// spectrum by this when "normalize" is requested, so the light's scale becomes its luminance.
float luminance(const Spectrum& s);

RGB xyz_to_linear_srgb(const XYZ& xyz);
// ACEScg with a Bradford adaptation D65 → ACES white: the renderer's reference white
// is D65 (the sRGB output's), so a surface that is neutral in sRGB stays neutral
// (r = g = b) in ACEScg, as in the ACES reference transforms from Rec. 709.
RGB xyz_to_acescg(const XYZ& xyz);

// The sRGB transfer curve (IEC 61966-2-1), linear -> encoded; no clamping.
float srgb_encode(float linear);

}  // namespace chlorovdb
