#include "spectra/library.h"

#include <fmt/format.h>

#include <array>
#include <cstdlib>
#include <map>
#include <mutex>

#include "core/error.h"
#include "spectra/csv.h"

namespace chlorovdb {

namespace {

struct NamedTable {
  std::string_view name, file, column;
};

constexpr std::array kNamedTables = {
    NamedTable{"D65", "cie_d65.csv", "value"},
    NamedTable{"F2", "cie_f2.csv", "value"},
    NamedTable{"UVB", "uvb_lamp.csv", "value"},
    NamedTable{"UVB-TL12", "uvb_lamp_philips_tl12_40w.csv", "value"},
    NamedTable{"water", "water_absorption_ioccg2018.csv", "a_per_m"},
    NamedTable{"water_pope_fry", "water_absorption_pope_fry.csv", "a_per_m"},
    NamedTable{"water_segelstein", "water_absorption_segelstein.csv", "a_per_m"},
    NamedTable{"water_refractive_index", "water_refractive_index.csv", "value"},
    NamedTable{"chlorophyll_a", "chlorophyll_a_molar_extinction.csv", "value"},
    NamedTable{"chlorophyll_a_emission", "chlorophyll_a_emission.csv", "value"},
    NamedTable{"fluspect_psi", "fluspect_emission.csv", "phiI"},
    NamedTable{"fluspect_psii", "fluspect_emission.csv", "phiII"},
    NamedTable{"prospect_chl_ab", "prospect_chl_sac.csv", "value"},
};

}  // namespace

std::filesystem::path spectra_dir() {
  const char* env = std::getenv("CHLOROVDB_SPECTRA");
  return (env && *env) ? std::filesystem::path(env) : std::filesystem::path(CHLOROVDB_SPECTRA_DIR);
}

std::vector<std::string> spectrum_names() {
  std::vector<std::string> names;
  for (const NamedTable& t : kNamedTables) names.emplace_back(t.name);
  return names;
}

Spectrum named_spectrum(std::string_view name) {
  for (const NamedTable& t : kNamedTables) {
    if (t.name != name) continue;
    // Keyed by the full path so a changed CHLOROVDB_SPECTRA loads the other folder's table.
    const std::filesystem::path path = spectra_dir() / t.file;
    const std::string key = fmt::format("{}#{}", path.string(), t.column);
    static std::mutex mutex;
    static std::map<std::string, Spectrum> cache;
    std::lock_guard lock(mutex);
    auto it = cache.find(key);
    if (it == cache.end()) it = cache.emplace(key, load_spectrum_csv(path, t.column)).first;
    return it->second;
  }
  const std::vector<std::string> names = spectrum_names();
  const std::string nearest = nearest_word(name, names);
  throw InputError(fmt::format("unknown spectrum name '{}'{}; known names: {}", name,
                               nearest.empty() ? "" : fmt::format(" (did you mean '{}'?)", nearest), fmt::join(names, ", ")));
}

}  // namespace chlorovdb
