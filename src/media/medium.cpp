#include "media/medium.h"

#include <cmath>
#include <fmt/format.h>

#include "core/error.h"

namespace chlorovdb {
namespace {

void check_field(const Field& f, const std::string& where, const std::string& key) {
  if (f.grid) {
    if (!(f.scale >= 0.f) || !std::isfinite(f.scale))
      throw InputError(where, key + ".scale", fmt::format("{}", f.scale), "must be finite and >= 0");
  } else if (!(f.value >= 0.f) || !std::isfinite(f.value)) {
    throw InputError(where, key, fmt::format("{}", f.value), "must be finite and >= 0");
  }
}

}  // namespace

Medium::Medium(MediumDesc desc) : desc_(std::move(desc)) {
  const std::string& where = desc_.where;
  if (desc_.pigments.size() > size_t(kMaxPigments))
    throw InputError(where, "pigments", fmt::format("{} pigments", desc_.pigments.size()),
                     fmt::format("a medium holds at most {}", kMaxPigments));
  if (desc_.majorant_voxels_per_cell < 0)
    throw InputError(where, "majorant_voxels_per_cell", fmt::format("{}", desc_.majorant_voxels_per_cell),
                     "must be >= 1, or 0 to choose from the medium's optical thickness");
  if (const auto* hg = std::get_if<HenyeyGreenstein>(&desc_.particle_phase); hg && !(std::fabs(hg->g) < 1.f))
    throw InputError(where, "particles.g", fmt::format("{}", hg->g), "must be in (-1, 1)");

  // One channel per distinct grid, so a grid shared by several fields is looked up once.
  auto channel_of = [&](const Field& f) {
    if (!f.grid) return -1;
    for (size_t c = 0; c < channels_.size(); ++c)
      if (channels_[c].grid == f.grid.get()) return int(c);
    channels_.push_back({f.grid.get(), true, Transform()});
    return int(channels_.size()) - 1;
  };
  for (size_t k = 0; k < desc_.pigments.size(); ++k) {
    const PigmentInMedium& p = desc_.pigments[k];
    const std::string key = fmt::format("pigments[{}]", k);
    validate(p.pigment, where, key);
    check_field(p.concentration, where, key + ".concentration");
    pigment_channel_[k] = channel_of(p.concentration);
    pigment_scale_[k] = p.concentration.scale;
    pigment_constant_[k] = p.concentration.value;
  }
  if (desc_.solvent.rayleigh && !(desc_.solvent.eta(550.f) >= 1.f))
    throw InputError(where, "solvent.eta", desc_.solvent.eta.source(),
                     "molecular scattering needs the solvent's refractive index (>= 1)");
  check_field(desc_.particle_sigma_s, where, "particles.sigma_s");
  particle_channel_ = channel_of(desc_.particle_sigma_s);
  if (channels_.empty()) return;

  // The medium's index space is that of its first grid.
  world_from_index_ = channels_[0].grid->world_from_index();
  index_from_world_ = channels_[0].grid->index_from_world();
  std::vector<const VoxelGrid*> grids;
  for (Channel& c : channels_) {
    c.grid_from_medium_index = c.grid->index_from_world() * world_from_index_;
    c.same_space = c.grid_from_medium_index.is_identity();
    grids.push_back(c.grid);
  }
  if (channels_.size() == 1 && channels_[0].same_space) single_grid_ = channels_[0].grid;
  // The majorant grid covers every grid's support at the first grid's voxels: grids
  // placed apart (one read in another length unit is 1000 times larger) would need
  // one too large to build. Say so by name rather than fail to allocate it.
  const Vec3 span = grid_region()->index_bounds.diagonal();
  const double smallest_cell = kMajorantCellSizes.front();
  const double majorant_bytes = (double(span.x) / smallest_cell + 1) * (double(span.y) / smallest_cell + 1) *
                                (double(span.z) / smallest_cell + 1) * 3.0 * double(channels_.size()) * sizeof(float);
  if (!(majorant_bytes < kMaxMajorantBytes))
    throw InputError(where, "grids",
                     fmt::format("{:.3g} x {:.3g} x {:.3g} voxels of its first grid", span.x, span.y, span.z),
                     fmt::format("the medium's grids together span too much for their majorant grid ({:.3g} GB): "
                                 "are they placed apart, or read in different length units (each grid's "
                                 "\"length_unit\")?",
                                 majorant_bytes / 1e9));
  if (desc_.majorant_voxels_per_cell > 0) {
    majorants_ = MajorantGrid(grids, desc_.majorant_voxels_per_cell, desc_.interpolation);
    return;
  }
  // sigma_t per unit of each grid's value, averaged over wavelengths the renderer draws.
  const PreparedMedium pm = prepare(*this, SampledWavelengths::sample_visible(0.5f, kMaxWavelengths));
  std::array<float, kMaxMajorantChannels> sigma_per_value{};
  for (int c = 0; c < channels(); ++c) sigma_per_value[c] = pm.channel_sigma_t[c].average(kMaxWavelengths);
  const float voxel_length = std::cbrt(length(world_from_index_.vector({1.f, 0.f, 0.f})) *
                                       length(world_from_index_.vector({0.f, 1.f, 0.f})) *
                                       length(world_from_index_.vector({0.f, 0.f, 1.f})));
  double least = 0.0;
  for (const int size : kMajorantCellSizes) {
    MajorantGrid candidate(grids, size, desc_.interpolation);
    const double cost = candidate.tracking_cost(std::span(sigma_per_value).first(channels()), voxel_length,
                                                kSegmentCostInCollisions);
    // The first candidate is taken whatever its cost: with extreme coefficients every cost is inf.
    if (majorants_.channels() == 0 || cost < least) {
      majorants_ = std::move(candidate);
      least = cost;
    }
  }
}

std::optional<Medium::GridRegion> Medium::grid_region() const {
  if (homogeneous()) return std::nullopt;
  Bounds3 b;
  for (const Channel& c : channels_) {
    const Bounds3 g = c.grid->index_bounds(desc_.interpolation);
    if (g.empty()) continue;
    const Transform medium_from_grid = c.grid_from_medium_index.inverse();
    for (int i = 0; i < 8; ++i)
      b.extend(medium_from_grid.point({i & 1 ? g.hi.x : g.lo.x, i & 2 ? g.hi.y : g.lo.y, i & 4 ? g.hi.z : g.lo.z}));
  }
  return GridRegion{b, world_from_index_};
}

PreparedMedium prepare(const Medium& medium, const SampledWavelengths& lambda) {
  const MediumDesc& d = medium.desc_;
  PreparedMedium pm;
  pm.lambda_count = lambda.count();
  // Grey quantities fill only the lanes the path carries.
  SampledSpectrum lanes;
  for (int i = 0; i < lambda.count(); ++i) lanes[i] = 1.f;

  pm.sigma_a_constant = d.solvent.absorption.sample(lambda);
  if (d.solvent.rayleigh) {
    const SampledSpectrum eta = d.solvent.eta.sample(lambda);
    for (int i = 0; i < lambda.count(); ++i)
      pm.sigma_s_molecular[i] = water_rayleigh_sigma_s(lambda[i], eta[i], d.solvent.temperature_K);
  }
  for (size_t k = 0; k < d.pigments.size(); ++k) {
    pm.sigma_a_per_molar[k] = d.pigments[k].pigment.epsilon.sample(lambda) * kAbsorptionPerMolarExtinction;
    const int c = medium.pigment_channel_[k];
    if (c < 0) pm.sigma_a_constant += pm.sigma_a_per_molar[k] * medium.pigment_constant_[k];
    else pm.channel_sigma_t[c] += pm.sigma_a_per_molar[k] * medium.pigment_scale_[k];
  }
  if (medium.particle_channel_ < 0) {
    pm.sigma_s_particle_constant = lanes * d.particle_sigma_s.value;
  } else {
    pm.sigma_s_particle_per_value = lanes * d.particle_sigma_s.scale;
    pm.channel_sigma_t[medium.particle_channel_] += pm.sigma_s_particle_per_value;
  }
  pm.sigma_t_constant = pm.sigma_a_constant + pm.sigma_s_molecular + pm.sigma_s_particle_constant;
  auto is_grey = [&](const SampledSpectrum& s) {
    for (int i = 1; i < lambda.count(); ++i)
      if (s[i] != s[0]) return false;
    return true;
  };
  pm.grey = is_grey(pm.sigma_t_constant);
  for (int c = 0; c < medium.channels(); ++c) pm.grey = pm.grey && is_grey(pm.channel_sigma_t[c]);
  return pm;
}

Medium::ChannelValues Medium::channel_values_of_each_grid(const Vec3& p_index) const {
  ChannelValues values{};
  for (size_t c = 0; c < channels_.size(); ++c) {
    const Channel& ch = channels_[c];
    const Vec3 p = ch.same_space ? p_index : ch.grid_from_medium_index.point(p_index);
    values[c] = ch.grid->lookup(p, desc_.interpolation);
  }
  return values;
}

MediumScattering Medium::scattering(const ChannelValues& v, const PreparedMedium& prepared) const {
  MediumScattering ms;
  ms.phase.particle = desc_.particle_phase;
  // Lane by lane over the carried wavelengths only: this runs at every real collision.
  for (int i = 0; i < prepared.lambda_count; ++i) {
    const float particle = sigma_s_particle(v, prepared, i);
    const float sigma_s = prepared.sigma_s_molecular[i] + particle;
    ms.sigma_s[i] = sigma_s;
    ms.phase.particle_fraction[i] = sigma_s > 0.f ? particle / sigma_s : 0.f;
  }
  return ms;
}

MediumProperties Medium::properties(const ChannelValues& v, const PreparedMedium& prepared) const {
  MediumProperties mp;
  const MediumScattering ms = scattering(v, prepared);
  mp.sigma_s = ms.sigma_s;
  mp.phase = ms.phase;
  const int pigments = pigment_count();
  for (int k = 0; k < pigments; ++k) mp.concentration[k] = pigment_concentration(v, k);
  for (int i = 0; i < prepared.lambda_count; ++i) {
    float sigma_a = prepared.sigma_a_constant[i];  // holds the constant pigments already
    for (int k = 0; k < pigments; ++k) {
      const float sigma_a_k = prepared.sigma_a_per_molar[k][i] * mp.concentration[k];
      mp.sigma_a_pigment[k][i] = sigma_a_k;
      if (pigment_channel_[k] >= 0) sigma_a += sigma_a_k;
    }
    mp.sigma_a[i] = sigma_a;
  }
  return mp;
}

}  // namespace chlorovdb
