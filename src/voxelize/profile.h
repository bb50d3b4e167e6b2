#pragma once
// Concentration profiles: the value a voxelized body holds at a world point,
// given how deep that point lies inside the body. No OpenVDB here.
//
//   uniform   C everywhere inside.
//   linear    C0 at the low end of the body's world box along `axis`, C1 at the high end, linear between.
//   noise     C · max(0, 1 + a · n(x / s)): n is seeded fractal value noise in [-1, 1]
//             (OpenVDB has none), s the feature size of its first octave, a the amplitude.
//   falloff   C · f(d / L), d the world distance inside from the body's surface:
//             decay f = exp(-d/L) (pigment concentrated at the surface), rise f = 1 - exp(-d/L) (soft edge).
//   grid      the concentration of another .vdb grid (value × its scale, converted from its unit to ours),
//             trilinear at the voxel centre; C is not used.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "core/vec.h"

namespace chlorovdb {

class VoxelGrid;

enum class ProfileKind { uniform, linear, noise, falloff, grid };
enum class FalloffShape { decay, rise };

struct ConcentrationProfile {
  ProfileKind kind = ProfileKind::uniform;
  float concentration = 1.f;       // C, in the output unit: uniform value, noise mean, falloff peak
  float c0 = 0.f, c1 = 1.f;        // linear: C at the low and the high end of the body, output unit
  int axis = 1;                    // linear: 0 = x, 1 = y, 2 = z (world)
  uint64_t seed = 1;               // noise
  float noise_scale = 0.f;         // noise: feature size of the first octave, metres (0: body's largest extent / 4)
  float noise_amplitude = 0.5f;    // noise: relative modulation a, in [0, 1]
  int noise_octaves = 3;           // noise: octaves of fractal sum (each half the size and amplitude), 1..8
  float falloff_length = 0.f;      // falloff: length scale L, metres
  FalloffShape falloff_shape = FalloffShape::decay;
  std::filesystem::path grid_file; // grid: source .vdb
  std::string grid_name = "density";
};

// Parses "uniform" | "linear" | "noise" | "falloff" | "grid"; false if the word is none of them.
bool parse_profile_kind(std::string_view word, ProfileKind* kind);
std::string_view to_string(ProfileKind kind);
std::string_view to_string(FalloffShape shape);
bool parse_falloff_shape(std::string_view word, FalloffShape* shape);  // "decay" | "rise"

// Factor from a concentration unit to mol/L ("M" = "mol/L", "mM", "uM" = "µM", "nM"); 0 if unknown.
double molar_per_unit(std::string_view unit);

// Seeded value noise on the integer lattice, smooth (quintic) between lattice points; in [-1, 1].
float value_noise(const Vec3& p, uint64_t seed);
// Sum of `octaves` value-noise octaves (frequency ×2, amplitude ×½ each), normalised to [-1, 1].
float fractal_noise(const Vec3& p, uint64_t seed, int octaves);

// A profile made ready to evaluate: parameters checked, the source grid loaded.
// Evaluation is const and thread-safe.
class ProfileSampler {
 public:
  // Throws InputError naming `source` (the mesh file) and the option for a bad
  // parameter, and whatever load_concentration_grid throws for the grid profile.
  // `body` is the world box of the voxelized body (linear end points, noise default size);
  // `unit` the output unit the values are given in.
  ProfileSampler(const ConcentrationProfile& profile, const Bounds3& body, std::string_view unit,
                 std::string_view source);
  ~ProfileSampler();
  ProfileSampler(ProfileSampler&&) noexcept;

  // Concentration (output unit) at world point p lying `depth` metres inside the body's surface.
  float value(const Vec3& p_world, float depth) const;
  // True when the value depends on p beyond the depth (linear, noise, grid): interior tiles must become voxels.
  bool varies_with_position() const;
  // Depth below which value() depends on the depth (falloff: where f is within 1e-4 of its limit); 0 otherwise.
  float depth_range() const;
  // Value deep inside (depth → ∞) for a profile that does not vary with position.
  float deep_value() const { return value(Vec3(0.f), 3e38f); }
  // The profile as command-line options, for provenance.
  std::string describe() const;

 private:
  ConcentrationProfile profile_;
  Bounds3 body_;
  float noise_scale_ = 1.f;
  float grid_factor_ = 1.f;  // source value -> output unit
  std::unique_ptr<VoxelGrid> grid_;
};

}  // namespace chlorovdb
