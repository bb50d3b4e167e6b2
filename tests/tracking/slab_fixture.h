#pragma once
// Media whose optical depth along a ray is known exactly: a homogeneous slab,
// and a concentration that varies piecewise-linearly along index x only
// (trilinear interpolation reproduces linear pieces exactly; kinks sit on voxel
// centres), under a rotated, non-uniformly scaled grid transform.
#include <cmath>
#include <functional>
#include <memory>
#include <vector>

#include "core/rng.h"
#include "media/medium.h"
#include "test_seed.h"

namespace chlorovdb::test {

// Four carried wavelengths; the pigment's extinction eps(l) = 100 (l - 400) gives the lanes
// optical depths in the ratios 25 : 5 : 15 : 30 (the hero, lane 0, in the middle).
inline const float kLambda[] = {650.f, 450.f, 550.f, 700.f};
inline const float kLambdaPdf[] = {1.f, 1.f, 1.f, 1.f};
inline SampledWavelengths four_wavelengths() { return SampledWavelengths::from_values(kLambda, kLambdaPdf, 4); }
inline Pigment ramp_pigment() {
  return {"ramp", Spectrum::tabulated({400.f, 800.f}, {0.f, 40000.f}), Spectrum::constant(0.f), 0.f};
}
inline constexpr float kWaterAbsorption = 0.05f;  // 1/m, all lanes

// sigma_t per lane for concentration c (mol/L), computed from the definitions.
inline double sigma_t_of(double c, int lane) {
  const double eps = 100.0 * (kLambda[lane] - 400.0);
  return kWaterAbsorption + water_rayleigh_sigma_s(kLambda[lane], 1.337f, 293.f) + 100.0 * std::log(10.0) * eps * c;
}

struct Slab {
  std::shared_ptr<Medium> medium;
  Ray ray;       // world space, not unit length
  float t_max;   // in the ray's parameter
  double tau[4];  // exact optical depth per lane over [0, t_max]
  std::function<double(double distance, int lane)> tau_to;  // exact optical depth over the first `distance` metres
};

inline MediumDesc water_desc() {
  MediumDesc d;
  d.solvent = Solvent::water(Spectrum::constant(kWaterAbsorption), Spectrum::constant(1.337f));
  return d;
}

// Homogeneous: optical depth tau for the hero over a 0.3 m long ray.
inline Slab homogeneous_slab(double tau_hero) {
  const double length = 0.3;
  const double sigma_base = sigma_t_of(0.0, 0);
  const double c = (tau_hero / length - sigma_base) / (sigma_t_of(1.0, 0) - sigma_base);
  MediumDesc d = water_desc();
  d.pigments.push_back({ramp_pigment(), Field::constant(float(c))});
  Slab s{std::make_shared<Medium>(d), Ray{{0.1f, 0.2f, 0.3f}, Vec3{0.6f, 0.f, 0.8f} * 2.f}, float(length / 2.0), {}, {}};
  s.tau_to = [c](double distance, int lane) { return sigma_t_of(c, lane) * distance; };
  for (int l = 0; l < 4; ++l) s.tau[l] = s.tau_to(length, l);
  return s;
}

// Integral over x in [a, b] of the function that is values[i] at x = i, linear between
// integers, and `outside` (0) at every integer beyond the table.
inline double integrate_piecewise_linear(const std::vector<double>& values, double a, double b) {
  if (a > b) std::swap(a, b);
  auto value_at = [&](long i) { return i >= 0 && i < long(values.size()) ? values[i] : 0.0; };
  auto f = [&](double x) {
    const long i = long(std::floor(x));
    const double w = x - double(i);
    return (1 - w) * value_at(i) + w * value_at(i + 1);
  };
  double sum = 0, x = a;
  while (x < b) {
    const double next = std::min(b, std::floor(x) + 1.0);
    sum += 0.5 * (f(x) + f(next)) * (next - x);  // exact: f is linear on [x, next]
    x = next;
  }
  return sum;
}

// Concentration varying along index x as values[i] * scale mol/L, with the scale set for
// tau_hero. The ray stays inside the grid in y and z; along x it runs from outside the grid
// (x = -6) to outside (x = n + 6), crossing the ramps down to the background at both ends,
// or (inside_only) from x = 1.5 to x = n - 2.5.
inline Slab piecewise_linear_slab(double tau_hero, const std::vector<double>& values, int voxels_per_cell = 8,
                                  bool inside_only = false) {
  // Wide in y and z, so that the cells the ray crosses do not reach the grid's
  // side faces (there a cell's minimum would be the background 0).
  const int nx = int(values.size()), ny = 40, nz = 40;
  DenseGrid g({nx, ny, nz});
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) g.at(x, y, z) = float(values[x]);
  g.world_from_index = Transform::translate({0.2f, -0.1f, 0.05f}) * Transform::rotate(25.f, {0.2f, 1.f, 0.3f}) *
                       Transform::scale({0.004f, 0.01f, 0.007f});
  const auto grid = std::make_shared<const VoxelGrid>(VoxelGrid::from_dense(g));
  // Index-space end points, mapped to world.
  const Vec3 a_index{inside_only ? 1.5f : -6.f, 15.2f, 14.5f},
      b_index{float(nx) + (inside_only ? -2.5f : 6.f), 27.9f, 28.1f};
  const Vec3 a = g.world_from_index.point(a_index), b = g.world_from_index.point(b_index);
  const Ray ray{a, (b - a) * 0.5f};  // t in [0, 2] spans the segment
  const double length = double(chlorovdb::length(b - a));
  // Integral of the index-x profile along the ray, in metres: dt_world = length / (x_b - x_a) dx.
  const double profile = integrate_piecewise_linear(values, a_index.x, b_index.x) * length / double(b_index.x - a_index.x);

  const double sigma_base = sigma_t_of(0.0, 0), per_molar = sigma_t_of(1.0, 0) - sigma_base;
  const double scale = (tau_hero - sigma_base * length) / (per_molar * profile);
  MediumDesc d = water_desc();
  d.pigments.push_back({ramp_pigment(), Field::from_grid(grid, float(scale))});
  d.majorant_voxels_per_cell = voxels_per_cell;
  Slab s{std::make_shared<Medium>(d), ray, 2.f, {}, {}};
  s.tau_to = [=](double distance, int lane) {
    const double x = a_index.x + (b_index.x - a_index.x) * distance / length;
    const double integral = integrate_piecewise_linear(values, a_index.x, x) * length / double(b_index.x - a_index.x);
    return sigma_t_of(0.0, lane) * distance + (sigma_t_of(1.0, lane) - sigma_t_of(0.0, lane)) * scale * integral;
  };
  for (int l = 0; l < 4; ++l) s.tau[l] = s.tau_to(length, l);
  return s;
}

// The slab's grid holding a grey absorber and grey particles instead of the ramp
// pigment in water (prepare() finds it grey); *tau: its exact optical depth along s.ray.
inline std::shared_ptr<Medium> grey_medium_on(const Slab& s, double* tau) {
  const Field& field = s.medium->desc().pigments[0].concentration;
  const double length = double(s.t_max) * double(chlorovdb::length(s.ray.d));
  // scale x integral of the profile along the ray, from the ramp slab's exact depth.
  const double c_integral = (s.tau_to(length, 0) - sigma_t_of(0.0, 0) * length) / (sigma_t_of(1.0, 0) - sigma_t_of(0.0, 0));
  MediumDesc d;
  d.solvent = Solvent::none();
  const float eps = 25000.f;  // L/(mol cm): sigma_a = 100 ln10 eps c; tau about 2 on the rough slab
  d.pigments.push_back({{"grey", Spectrum::constant(eps), Spectrum::constant(0.f), 0.f}, field});
  d.particle_sigma_s = Field::from_grid(field.grid, 3.f * field.scale);  // 3 /m per mol/L
  d.majorant_voxels_per_cell = s.medium->desc().majorant_voxels_per_cell;
  *tau = (100.0 * std::log(10.0) * eps + 3.0) * c_integral;
  return std::make_shared<Medium>(d);
}

// Piecewise-linear profiles: a rough one with a run of empty voxels and sharp
// kinks, and a gentle one (for thick media, where only a small residual is tracked).
inline std::vector<double> rough_profile() {
  std::vector<double> v(64);
  Rng rng(test_seed(42), 0);
  for (int i = 0; i < 64; ++i) v[i] = (i >= 24 && i < 40) ? 0.0 : 0.2 + 1.6 * rng.uniform();
  return v;
}
inline std::vector<double> gentle_profile() {
  std::vector<double> v(64);
  Rng rng(test_seed(43), 0);
  for (int i = 0; i < 64; ++i) v[i] = 0.9 + 0.2 * rng.uniform();
  return v;
}

}  // namespace chlorovdb::test
