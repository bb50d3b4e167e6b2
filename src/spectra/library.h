#pragma once
// The spectral tables shipped in spectra/ (provenance: spectra/SOURCES.md), by name.
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "spectra/spectrum.h"

namespace chlorovdb {

// Folder of the CSV tables: $CHLOROVDB_SPECTRA if set, else the build's CHLOROVDB_SPECTRA_DIR.
std::filesystem::path spectra_dir();

// "D65", "F2" (CIE illuminants, relative), "UVB" (Q-Panel UVB-313), "UVB-TL12" (Philips TL 40W/12),
// "water" (IOCCG 2018 a_w, 1/m), "water_pope_fry" (1/m), "water_segelstein" (1/m),
// "water_refractive_index" (n), "chlorophyll_a" (decadic ε, L/mol/cm, diethyl ether, ends at 700 nm),
// "chlorophyll_a_emission" (relative, not normalised), "fluspect_psi" / "fluspect_psii"
// (leaf PSI / PSII emission, per nm), "prospect_chl_ab" (in-vivo Chl a+b, cm²/µg).
// Tables are loaded once and cached (thread-safe). Unknown names throw InputError with the nearest name.
Spectrum named_spectrum(std::string_view name);
std::vector<std::string> spectrum_names();

}  // namespace chlorovdb
