#include "scene/medium_param.h"

#include <fmt/format.h>

#include "core/error.h"
#include "fluorescence/emission_spectrum.h"
#include "grids/vdb_file.h"
#include "scene/spectrum_param.h"
#include "spectra/library.h"

namespace chlorovdb {

namespace {

Spectrum read_emission(ParamReader& p, const Spectrum& epsilon, float quantum_yield) {
  const std::string fallback = quantum_yield > 0.f ? "mirror" : "none";
  if (p.has("emission") && !p.raw("emission").is_string()) return normalise_emission(read_spectrum(p, "emission"));
  const std::string kind = p.get_string("emission", fallback);
  if (kind == "none") return Spectrum::constant(0.f);
  if (kind == "gaussian") return gaussian_emission();
  if (kind == "mirror") {
    MirrorImageBand band;
    band.mirror_nm = p.get_float("mirror_nm", band.mirror_nm, kLambdaMinUV, kLambdaMax);
    const auto b = p.get_floats("mirror_band", {band.band_min_nm, band.band_max_nm}, 2);
    if (b.size() != 2 || !(b[0] < b[1])) p.fail("mirror_band", "expected [min_nm, max_nm] with min < max");
    band.band_min_nm = b[0];
    band.band_max_nm = b[1];
    try {
      return mirror_image_emission(epsilon, band);
    } catch (const std::invalid_argument& e) {
      p.fail("emission", e.what());
    }
  }
  // Any other string is a spectrum (a table name or a CSV path).
  try {
    return normalise_emission(read_spectrum(p, "emission"));
  } catch (const std::invalid_argument& e) {
    p.fail("emission", e.what());
  }
}

// Largest concentration and scattering coefficient a field may reach. No solution
// holds more than ~55 mol/L of anything (water itself), and a coefficient of
// 1e12 /m is an optical depth of 1e6 per micrometre; beyond these the
// coefficients overflow single precision or tracking in a grid never ends.
constexpr double kMaxConcentrationMolar = 100.0;
constexpr double kMaxCoefficientPerMetre = 1e12;

void check_field_maximum(ParamReader& p, const std::string& key, double max_internal, bool concentration) {
  const double limit = concentration ? kMaxConcentrationMolar : kMaxCoefficientPerMetre;
  if (max_internal <= limit) return;
  p.fail(key, concentration ? fmt::format("reaches {:.3g} mol/L (values x scale x unit); at most {:g} mol/L", max_internal, limit)
                            : fmt::format("reaches {:.3g} /m (values x scale); at most {:g} /m", max_internal, limit));
}

// A concentration or coefficient: a number, or {"file", "name", "scale", "unit", "length_unit"}.
Field read_field(ParamReader& p, const std::string& key, bool concentration, GridCache& grids) {
  const nlohmann::json& v = p.raw(key);
  if (v.is_number()) {
    const float value = p.require_float(key, 0.f);
    const float to_internal =
        concentration ? molar_per_unit(p.get_string("unit", "uM"), p.file().string(), p.key_path("unit")) : 1.f;
    check_field_maximum(p, key, double(value) * to_internal, concentration);
    return Field::constant(value * to_internal);
  }
  ParamReader g = p.child(key);
  const std::filesystem::path file = g.require_path("file");
  const std::string name = g.get_string("name", "density");
  const float scale = g.get_float("scale", 1.f, 0.f);
  // The grid's transform is in its own length unit: the scene's word, else the
  // grid's "length_unit" metadata, else metres (what voxelize writes).
  const std::string length_unit = g.has("length_unit") ? g.get_enum("length_unit", "m", kLengthUnits) : "";
  GridLoadOptions options;
  options.clamp_invalid = g.get_bool("clamp_invalid", false);
  auto& grid = grids[{file.string(), name, length_unit}];
  if (!grid) {
    VoxelGrid loaded = load_concentration_grid(file, name, options);
    const std::string& own = loaded.metadata().length_unit;
    const std::string word = !length_unit.empty() ? length_unit : own.empty() ? "m" : own;
    const float metres = metres_per_length_unit(word);
    if (metres == 0.f)
      throw InputError(file.string(), fmt::format("grid {}: metadata length_unit", name), word,
                       fmt::format("unknown length unit; use one of {} (or set {} in the scene)",
                                   fmt::join(kLengthUnits, ", "), g.key_path("length_unit")));
    if (metres != 1.f)
      loaded.set_world_from_index(Transform::scale(Vec3(metres)) * loaded.world_from_index());
    grid = std::make_shared<const VoxelGrid>(std::move(loaded));
  }
  float to_internal = 1.f;
  if (concentration) {
    // Unit: the scene's word, else the grid's own metadata, else µM (the literature's unit).
    const std::string unit = g.get_string("unit", grid->metadata().unit.empty() ? "uM" : grid->metadata().unit);
    to_internal = molar_per_unit(unit, p.file().string(), g.key_path("unit"));
  }
  g.finish();
  const double factor = double(scale) * grid->metadata().scale * to_internal;
  check_field_maximum(p, key, factor * grid->max_value(), concentration);
  return Field::from_grid(grid, float(factor));
}

}  // namespace

const std::vector<std::string> kLengthUnits{"m", "cm", "mm", "um"};

float metres_per_length_unit(const std::string& unit) {
  if (unit == "m") return 1.f;
  if (unit == "cm") return 1e-2f;
  if (unit == "mm") return 1e-3f;
  if (unit == "um") return 1e-6f;
  return 0.f;
}

PigmentTable read_pigments(ParamReader& top) {
  PigmentTable table;
  for (auto& [name, p] : top.children_map("pigments")) {
    PigmentDefinition def;
    def.pigment.name = name;
    def.pigment.epsilon = read_spectrum(p, "extinction").scaled(p.get_float("extinction_scale", 1.f, 1e-30f));
    def.pigment.quantum_yield = p.get_float("quantum_yield", 0.f, 0.f, 1.f);
    def.pigment.emission = read_emission(p, def.pigment.epsilon, def.pigment.quantum_yield);
    def.redistribution = p.get_enum("redistribution", "kasha_vavilov", {"kasha_vavilov", "stokes"}) == "stokes"
                             ? Redistribution::stokes
                             : Redistribution::kasha_vavilov;
    p.finish();
    validate(def.pigment, p.file().string(), p.key_path(""));
    table.emplace(name, std::move(def));
  }
  return table;
}

MediumDefinition read_medium(ParamReader& m, const PigmentTable& pigments, GridCache& grids) {
  MediumDesc desc;
  desc.where = fmt::format("{}: {}", m.file().string(), m.key_path(""));
  // Solvent.
  if (!m.has("solvent") || m.raw("solvent").is_string()) {
    const std::string s = m.get_enum("solvent", "water", {"water", "none"});
    desc.solvent = s == "water" ? Solvent::water(named_spectrum("water"), named_spectrum("water_refractive_index"))
                                : Solvent::none();
  } else {
    ParamReader s = m.child("solvent");
    desc.solvent.absorption = read_spectrum(s, "absorption", named_spectrum("water"));
    desc.solvent.rayleigh = s.get_bool("rayleigh", true);
    desc.solvent.eta = s.has("ior") ? Spectrum::constant(s.require_float("ior", 1.f, 3.f))
                                    : named_spectrum("water_refractive_index");
    desc.solvent.temperature_K = s.get_float("temperature", 293.f, 1.f, 1000.f);
    s.finish();
  }
  // Pigments.
  std::vector<FluorescentPigment> fluorescent;
  for (ParamReader& entry : m.children_array("pigments")) {
    const std::string name = entry.require_string("pigment");
    const auto it = pigments.find(name);
    if (it == pigments.end()) {
      std::vector<std::string> names;
      for (const auto& [n, d] : pigments) names.push_back(n);
      const std::string near = nearest_word(name, names);
      entry.fail("pigment", fmt::format("no pigment of that name in \"pigments\"{}",
                                        near.empty() ? "" : fmt::format(" (did you mean \"{}\"?)", near)));
    }
    if (entry.has("concentration") == entry.has("grid")) entry.fail("", "give either \"concentration\" or \"grid\"");
    PigmentInMedium pm{it->second.pigment, read_field(entry, entry.has("grid") ? "grid" : "concentration", true, grids)};
    entry.finish();
    if (int(desc.pigments.size()) == kMaxPigments)
      entry.fail("pigment", fmt::format("a medium holds at most {} pigments", kMaxPigments));
    if (pm.pigment.quantum_yield > 0.f && pm.pigment.emission.max_value() > 0.f) {
      FluorescentPigment fp;
      fp.pigment = int(desc.pigments.size());
      fp.quantum_yield = pm.pigment.quantum_yield;
      fp.epsilon = pm.pigment.epsilon;
      fp.emission = pm.pigment.emission;
      fp.redistribution = RedistributionWeight(it->second.redistribution, pm.pigment.emission);
      fluorescent.push_back(std::move(fp));
    }
    desc.pigments.push_back(std::move(pm));
  }
  // Particle scattering.
  if (auto s = m.optional_child("scattering")) {
    desc.particle_sigma_s = read_field(*s, "coefficient", false, grids);
    desc.particle_phase = HenyeyGreenstein{s->get_float("g", 0.f, -0.999f, 0.999f)};
    s->finish();
  }
  desc.interpolation = m.get_enum("interpolation", "trilinear", {"trilinear", "nearest"}) == "nearest"
                           ? Interpolation::nearest
                           : Interpolation::trilinear;
  m.finish();
  return {Medium(std::move(desc)), std::move(fluorescent)};
}

bool can_scatter(const Medium& medium) {
  const MediumDesc& d = medium.desc();
  const Field& p = d.particle_sigma_s;
  return d.solvent.rayleigh || p.grid || p.value > 0.f;
}

std::optional<Bounds3> medium_bounds(const Medium& medium) {
  const auto region = medium.grid_region();
  if (!region) return std::nullopt;
  Bounds3 world;
  const Bounds3& b = region->index_bounds;
  for (int c = 0; c < 8; ++c)
    world.extend(region->world_from_index.point({c & 1 ? b.hi.x : b.lo.x, c & 2 ? b.hi.y : b.lo.y,
                                                 c & 4 ? b.hi.z : b.lo.z}));
  return world;
}

}  // namespace chlorovdb
