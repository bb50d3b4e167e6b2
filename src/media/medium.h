#pragma once
// A participating medium: a solvent, up to kMaxPigments dissolved pigments
// (each a concentration grid or a constant) and optional particle scattering
// (a grid or a constant, with its own phase function). docs/physics.md §1, §2, §6:
//   sigma_a(x, l) = zeta_solvent(l) + sum_k 100 ln10 eps_k(l) c_k(x)
//   sigma_s(x, l) = sigma_s,Rayleigh(l) + sigma_s,particle(x)
// Units: concentrations mol/L, coefficients 1/m, lengths metres.
//
// Use: once per path (per set of wavelengths) `prepare`, which evaluates every
// spectrum at the path's wavelengths; then a collision costs one lookup per
// distinct grid and a few multiply-adds per lane (sample_point). Tracking
// (tracking/) walks majorant segments through `majorants`.
//
// A medium covers whatever ray segment [0, t_max] it is given: the scene decides
// its region (inside a closed mesh, or the grid's own bounds: grid_region()).
// A medium with no grid is homogeneous: one segment, and the closed-form
// transmittance applies.
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/transform.h"
#include "core/vec.h"
#include "grids/majorant_grid.h"
#include "grids/voxel_grid.h"
#include "media/medium_phase.h"
#include "media/phase.h"
#include "media/pigment.h"
#include "media/solvent.h"
#include "spectra/sampled.h"

namespace chlorovdb {

// Majorant cell edges, in voxels, a medium chooses from (MediumDesc::majorant_voxels_per_cell
// = 0): the one with the least tracking work for the medium's optical thickness, since
// finer cells bound sigma_t more tightly (fewer null collisions) but cost more segments.
inline constexpr std::array<int, 5> kMajorantCellSizes{4, 6, 8, 12, 16};
// The work of one majorant segment, in collisions (docs/performance.md).
inline constexpr float kSegmentCostInCollisions = 0.8f;
// The largest majorant grid a medium builds (its grids' span at the smallest cell).
inline constexpr double kMaxMajorantBytes = 4.0 * (1ull << 30);

// A scalar field: a grid, or a constant everywhere.
struct Field {
  std::shared_ptr<const VoxelGrid> grid;  // null: the field is `value` everywhere
  float value = 0.f;                      // the constant (internal unit), when grid is null
  float scale = 1.f;                      // grid value * scale = the field in its internal unit

  static Field constant(float value) { return {nullptr, value, 1.f}; }
  static Field from_grid(std::shared_ptr<const VoxelGrid> grid, float scale) { return {std::move(grid), 0.f, scale}; }
};

struct PigmentInMedium {
  Pigment pigment;
  Field concentration;  // mol/L (the scale folds in the grid's unit, e.g. 1e-6 for uM)
};

struct MediumDesc {
  std::string where;  // for error messages, e.g. "scene.json: media.leaf"
  Solvent solvent;
  std::vector<PigmentInMedium> pigments;  // at most kMaxPigments
  Field particle_sigma_s;                 // 1/m, the same at every wavelength; constant 0: no particles
  PhaseFunction particle_phase = HenyeyGreenstein{0.f};
  Interpolation interpolation = Interpolation::trilinear;
  int majorant_voxels_per_cell = 0;  // 0: chosen from kMajorantCellSizes for this medium
};

// Coefficients at one point, for the wavelengths of a PreparedMedium.
struct MediumProperties {
  SampledSpectrum sigma_a;  // 1/m: solvent + pigments
  SampledSpectrum sigma_s;  // 1/m: molecules + particles
  std::array<SampledSpectrum, kMaxPigments> sigma_a_pigment;  // each pigment's part of sigma_a
  std::array<float, kMaxPigments> concentration{};            // mol/L
  MediumPhase phase;
};

// What a scattering event needs of the medium at its point: a path scattering in
// a medium reads only these, so it skips the per-pigment absorption (a tenth of
// the work at each scattering event of a thick cloud).
struct MediumScattering {
  SampledSpectrum sigma_s;  // 1/m: molecules + particles
  MediumPhase phase;
};

// A medium's spectra evaluated at one path's wavelengths (prepare()).
struct PreparedMedium {
  int lambda_count = 0;
  SampledSpectrum sigma_a_constant;           // solvent + constant pigments
  SampledSpectrum sigma_s_molecular;          // Rayleigh
  SampledSpectrum sigma_s_particle_constant;  // constant particles (0 if they come from a grid)
  SampledSpectrum sigma_s_particle_per_value; // per unit value of the particle grid
  std::array<SampledSpectrum, kMaxPigments> sigma_a_per_molar;  // 100 ln10 eps_k(l): 1/m per mol/L
  // sigma_t = sigma_t_constant + sum over grids ("channels") of channel_sigma_t * value.
  SampledSpectrum sigma_t_constant;
  std::array<SampledSpectrum, kMaxMajorantChannels> channel_sigma_t;

  // sigma_t is the same on every carried lane (grey absorbers and scatterers, no
  // solvent): transmittance is then tracked on one lane (tracking/transmittance.cpp).
  bool grey = false;

  // Per-wavelength bounds of sigma_t over a majorant segment (docs/physics.md §6):
  // sigma_maj = zeta + 100 ln10 sum_k eps_k c_max,k + sigma_s,max; sigma_min likewise with c_min.
  // `lanes`: the first lanes to compute (the others come out 0); all carried lanes by default.
  SampledSpectrum sigma_maj(const MajorantSegment& s, int channels, int lanes) const {
    return sigma_t_for(s.c_max, channels, lanes);
  }
  SampledSpectrum sigma_min(const MajorantSegment& s, int channels, int lanes) const {
    return sigma_t_for(s.c_min, channels, lanes);
  }
  SampledSpectrum sigma_maj(const MajorantSegment& s, int channels) const { return sigma_maj(s, channels, lambda_count); }
  SampledSpectrum sigma_min(const MajorantSegment& s, int channels) const { return sigma_min(s, channels, lambda_count); }

  // sigma_t for the given channel values. Loops over the carried lanes only (the
  // others are zero in every prepared spectrum): this runs at every collision.
  template <typename Values>
  SampledSpectrum sigma_t_for(const Values& values, int channels, int lanes) const {
    SampledSpectrum s;
    for (int i = 0; i < lanes; ++i) s[i] = sigma_t_lane(values, channels, i);
    return s;
  }
  // One lane of it: a null collision in a grey medium, or a tracker that works lane
  // by lane, needs no SampledSpectrum (building one costs as much as the lookup).
  template <typename Values>
  float sigma_t_lane(const Values& values, int channels, int lane) const {
    float sigma = sigma_t_constant[lane];
    if (channels == 1) return sigma + channel_sigma_t[0][lane] * values[0];  // one grid, the common case
    for (int c = 0; c < channels; ++c) sigma += channel_sigma_t[c][lane] * values[c];
    return sigma;
  }
};

class Medium {
 public:
  // Validates (InputError naming desc.where) and builds the majorant grid over
  // the distinct grids (a grid shared by several fields is looked up once).
  explicit Medium(MediumDesc desc);

  const MediumDesc& desc() const { return desc_; }
  bool homogeneous() const { return channels_.empty(); }
  int pigment_count() const { return int(desc_.pigments.size()); }
  const MajorantGrid& majorant_grid() const { return majorants_; }
  int channels() const { return int(channels_.size()); }

  // The grids' region for media bounded by their grids: a box in the grid
  // index space (the union of every grid's support under the medium's
  // interpolation: VoxelGrid::index_bounds) and its transform to world. None for homogeneous media.
  struct GridRegion {
    Bounds3 index_bounds;
    Transform world_from_index;
  };
  std::optional<GridRegion> grid_region() const;

  // --- For tracking (tracking/): work in the medium's index space, where the
  // ray parameter t is the same as in world space.
  Ray index_ray(const Ray& world) const {
    return homogeneous() ? world : Ray{index_from_world_.point(world.o), index_from_world_.vector(world.d)};
  }
  Vec3 index_point(const Vec3& p_world) const { return homogeneous() ? p_world : index_from_world_.point(p_world); }
  MajorantIterator majorants(const Ray& ray_index, float t_max) const { return majorants_.segments(ray_index, t_max); }
  // True when pigment k's concentration comes from a grid (else it is a constant).
  bool pigment_in_grid(int k) const { return pigment_channel_[k] >= 0; }
  // No lookup along a majorant segment gives pigment k (a grid pigment) more than this, mol/L.
  float pigment_concentration_max(const MajorantSegment& s, int k) const {
    return s.c_max[pigment_channel_[k]] * pigment_scale_[k];
  }
  // The grids' values at one point (one lookup per distinct grid): every coefficient there
  // follows from them, so a caller that needs several looks up once.
  using ChannelValues = std::array<float, kMaxMajorantChannels>;
  inline ChannelValues channel_values(const Vec3& p_index) const;
  // Pigment k's concentration, mol/L, from the grids' values there.
  float pigment_concentration(const ChannelValues& v, int k) const {
    return pigment_channel_[k] >= 0 ? v[pigment_channel_[k]] * pigment_scale_[k] : pigment_constant_[k];
  }
  SampledSpectrum sigma_t(const ChannelValues& v, const PreparedMedium& prepared) const {
    return prepared.sigma_t_for(v, int(channels_.size()), prepared.lambda_count);
  }
  float sigma_t(const ChannelValues& v, const PreparedMedium& prepared, int lane) const {
    return prepared.sigma_t_lane(v, int(channels_.size()), lane);
  }
  // sigma_s on one lane (the hero's, to choose between absorption, scattering and null).
  float sigma_s(const ChannelValues& v, const PreparedMedium& prepared, int lane) const {
    return prepared.sigma_s_molecular[lane] + sigma_s_particle(v, prepared, lane);
  }
  MediumProperties properties(const ChannelValues& v, const PreparedMedium& prepared) const;
  MediumScattering scattering(const ChannelValues& v, const PreparedMedium& prepared) const;
  SampledSpectrum sigma_t(const Vec3& p_index, const PreparedMedium& prepared) const {
    return sigma_t(channel_values(p_index), prepared);
  }
  MediumProperties properties(const Vec3& p_index, const PreparedMedium& prepared) const {
    return properties(channel_values(p_index), prepared);
  }

 private:
  friend PreparedMedium prepare(const Medium& medium, const SampledWavelengths& lambda);
  // channel_values for several grids or a transformed one: out of line, so the
  // one-grid path stays small enough to inline at every collision.
  ChannelValues channel_values_of_each_grid(const Vec3& p_index) const;
  float sigma_s_particle(const ChannelValues& v, const PreparedMedium& prepared, int lane) const {
    const float particle_value = particle_channel_ < 0 ? 0.f : v[particle_channel_];
    return prepared.sigma_s_particle_constant[lane] + prepared.sigma_s_particle_per_value[lane] * particle_value;
  }
  // A distinct grid and how to reach its index space from the medium's.
  struct Channel {
    const VoxelGrid* grid;
    bool same_space;                     // its index space is the medium's
    Transform grid_from_medium_index;
  };

  MediumDesc desc_;
  std::vector<Channel> channels_;
  const VoxelGrid* single_grid_ = nullptr;  // the only channel, when it needs no transform
  // Per pigment: its channel (-1: constant) and the factor to mol/L or the constant itself.
  std::array<int, kMaxPigments> pigment_channel_{};
  std::array<float, kMaxPigments> pigment_scale_{}, pigment_constant_{};
  int particle_channel_ = -1;
  Transform index_from_world_, world_from_index_;
  MajorantGrid majorants_;
};

inline bool is_homogeneous(const Medium& medium) { return medium.homogeneous(); }

// Evaluates the medium's spectra at the path's wavelengths.
PreparedMedium prepare(const Medium& medium, const SampledWavelengths& lambda);

// Coefficients at a world-space point.
inline MediumProperties sample_point(const Medium& medium, const Vec3& p_world, const PreparedMedium& prepared) {
  return medium.properties(medium.index_point(p_world), prepared);
}

inline Medium::ChannelValues Medium::channel_values(const Vec3& p_index) const {
  ChannelValues values{};
  if (single_grid_) {  // one grid in the medium's own index space, the common case
    values[0] = single_grid_->lookup(p_index, desc_.interpolation);
    return values;
  }
  return channel_values_of_each_grid(p_index);
}

}  // namespace chlorovdb
