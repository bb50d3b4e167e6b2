#pragma once
// The liquid the pigments are dissolved in: its absorption and its molecular
// (Rayleigh / Einstein-Smoluchowski) scattering, docs/physics.md §2.
#include "spectra/spectrum.h"

namespace chlorovdb {

struct Solvent {
  Spectrum absorption;       // zeta(lambda), 1/m (water: the IOCCG 2018 a_w table, named_spectrum("water"))
  bool rayleigh = false;     // add molecular scattering with water's constants (water_rayleigh_sigma_s)
  Spectrum eta;              // real refractive index, for the Rayleigh term (water: named_spectrum("water_refractive_index"))
  float temperature_K = 293.f;

  static Solvent none() { return {}; }
  static Solvent water(Spectrum absorption, Spectrum eta, float temperature_K = 293.f) {
    return {std::move(absorption), true, std::move(eta), temperature_K};
  }
};

// Molecular scattering coefficient of water, 1/m: mu_s = (16 pi / 3) R90 with
// the Rayleigh ratio R90 = (pi^2 / 18) (beta R T / (N lambda^4)) (eta^2 - 1)^2 (eta^2 + 2)^2
// in cgs units, beta = 4.95e-11 cm^2/dyne (isothermal compressibility of water),
// R = 8.315e7 erg/(K mol), N = 6.06e23 /mol. About 2.6e-3 /m at 500 nm, eta = 1.337, 293 K.
float water_rayleigh_sigma_s(float lambda_nm, float eta, float temperature_K);

}  // namespace chlorovdb
