#pragma once
// Fluorescence emission spectra f(λ), normalised to unit integral per nm
// (docs/physics.md §3–§4). Three sources a user can pick: the mirror-image rule
// applied to the pigment's own absorption table, the ocean-optics Gaussian,
// or a measured table.
#include "spectra/spectrum.h"

namespace chlorovdb {

// Rescales `s` so that its integral over its support (at least 250–830 nm) is 1.
// Throws std::invalid_argument when the integral is zero.
Spectrum normalise_emission(const Spectrum& s);

struct MirrorImageBand {
  float mirror_nm = 673.f;  // the S0-S1 0-0 transition the band is mirrored about
  float band_min_nm = 600.f;  // the red (S1) absorption band only, not the Soret band
  float band_max_nm = 700.f;
};

// f(λ) ∝ ε(2·mirror − λ) for 2·mirror − λ inside the band, normalised.
// Tabulated on the mirrored wavelengths of ε's own samples (no resampling loss).
Spectrum mirror_image_emission(const Spectrum& epsilon, const MirrorImageBand& band = {});

// Gaussian emission used in ocean optics for chlorophyll a: peak 685 nm, σ = 10.6 nm.
Spectrum gaussian_emission(float peak_nm = 685.f, float sigma_nm = 10.6f);

}  // namespace chlorovdb
