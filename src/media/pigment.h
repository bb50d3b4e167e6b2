#pragma once
// A pigment: what it absorbs (decadic molar extinction) and, if fluorescent,
// what it emits and how efficiently (docs/physics.md §1, §3).
#include <string>
#include <string_view>

#include "core/constants.h"
#include "spectra/spectrum.h"

namespace chlorovdb {

inline constexpr int kMaxPigments = 4;

// mu_a [1/m] = kAbsorptionPerMolarExtinction * epsilon [L mol^-1 cm^-1] * c [mol/L]:
// ln 10 because tables are decadic (T = 10^(-eps c l)), 100 because they are per cm.
inline constexpr float kAbsorptionPerMolarExtinction = 100.f * kLn10;

struct Pigment {
  std::string name;
  Spectrum epsilon;           // decadic molar extinction, L mol^-1 cm^-1; zero beyond its table (never extrapolated)
  Spectrum emission;          // per nm, unit integral; zero for a pigment that does not fluoresce
  float quantum_yield = 0.f;  // Q in [0, 1]: photons emitted per photon absorbed
};

// Throws InputError naming file and key (e.g. "scene.json", "media.leaf.pigments[0]") when
// epsilon or emission is negative or not finite, Q is outside [0, 1], Q > 0 with a zero
// emission spectrum, or a non-zero emission spectrum does not integrate to 1 (within 0.1 %).
void validate(const Pigment& pigment, std::string_view file, std::string_view key);

// Factor from a concentration unit to mol/L: "M" (= "mol/L"), "mM", "uM" (= "µM"), "nM".
// Throws InputError naming file, key and the unit otherwise.
float molar_per_unit(std::string_view unit, std::string_view file, std::string_view key);

}  // namespace chlorovdb
