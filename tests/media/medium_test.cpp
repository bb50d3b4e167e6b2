#include <gtest/gtest.h>

#include "core/error.h"
#include "core/rng.h"
#include "media/medium.h"

using namespace chlorovdb;

namespace {

const float kLambda[] = {450.f, 550.f, 650.f, 700.f};
const float kPdf[] = {1.f, 1.f, 1.f, 1.f};
SampledWavelengths four_wavelengths() { return SampledWavelengths::from_values(kLambda, kPdf, 4); }

// A pigment whose extinction rises linearly with wavelength: eps(l) = 100 (l - 400).
Pigment ramp_pigment() {
  return {"ramp", Spectrum::tabulated({400.f, 800.f}, {0.f, 40000.f}), Spectrum::constant(0.f), 0.f};
}

std::shared_ptr<const VoxelGrid> ramp_grid() {
  DenseGrid d({16, 16, 16});
  for (int z = 0; z < 16; ++z)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) d.at(x, y, z) = float(x);
  d.world_from_index = Transform::scale({0.01f, 0.02f, 0.01f});
  return std::make_shared<const VoxelGrid>(VoxelGrid::from_dense(d));
}

}  // namespace

TEST(Medium, HomogeneousCoefficientsAddUp) {
  MediumDesc d;
  d.solvent = Solvent::water(Spectrum::constant(0.5f), Spectrum::constant(1.337f));
  d.pigments.push_back({ramp_pigment(), Field::constant(2e-6f)});
  d.particle_sigma_s = Field::constant(3.f);
  const Medium m(d);
  EXPECT_TRUE(is_homogeneous(m));
  const SampledWavelengths lambda = four_wavelengths();
  const PreparedMedium pm = prepare(m, lambda);
  const MediumProperties mp = sample_point(m, {1.f, 2.f, 3.f}, pm);
  for (int i = 0; i < 4; ++i) {
    const float eps = 100.f * (kLambda[i] - 400.f);
    const float pigment = kAbsorptionPerMolarExtinction * eps * 2e-6f;
    const float rayleigh = water_rayleigh_sigma_s(kLambda[i], 1.337f, 293.f);
    EXPECT_NEAR(mp.sigma_a[i], 0.5f + pigment, 1e-5f * mp.sigma_a[i]);
    EXPECT_NEAR(mp.sigma_a_pigment[0][i], pigment, 1e-5f * pigment + 1e-9f);
    EXPECT_NEAR(mp.sigma_s[i], 3.f + rayleigh, 1e-6f);
    EXPECT_NEAR(mp.phase.particle_fraction[i], 3.f / (3.f + rayleigh), 1e-6f);
    EXPECT_NEAR(pm.sigma_t_constant[i], mp.sigma_a[i] + mp.sigma_s[i], 1e-5f * pm.sigma_t_constant[i]);
  }
  EXPECT_EQ(mp.concentration[0], 2e-6f);
  // Lanes the path does not carry stay zero.
  EXPECT_EQ(mp.sigma_a[4], 0.f);
  EXPECT_EQ(mp.sigma_s[4], 0.f);
}

TEST(Medium, GridConcentrationIsLookedUpInWorldSpace) {
  const auto grid = ramp_grid();
  MediumDesc d;
  d.pigments.push_back({ramp_pigment(), Field::from_grid(grid, 1e-6f)});  // grid in uM
  d.particle_sigma_s = Field::from_grid(grid, 0.5f);                      // the same grid: one lookup
  const Medium m(d);
  EXPECT_FALSE(is_homogeneous(m));
  EXPECT_EQ(m.channels(), 1);
  const SampledWavelengths lambda = four_wavelengths();
  const PreparedMedium pm = prepare(m, lambda);
  // World x = 0.01 * index x, and the value is the index x.
  const MediumProperties mp = sample_point(m, {0.0725f, 0.1f, 0.05f}, pm);
  EXPECT_NEAR(mp.concentration[0], 7.25e-6f, 1e-10f);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(mp.sigma_a[i], kAbsorptionPerMolarExtinction * 100.f * (kLambda[i] - 400.f) * 7.25e-6f, 1e-3f);
    EXPECT_NEAR(mp.sigma_s[i], 0.5f * 7.25f, 1e-5f);
    EXPECT_EQ(mp.phase.particle_fraction[i], 1.f);  // no solvent: particles only
  }
  const SampledSpectrum st = m.sigma_t(m.index_point({0.0725f, 0.1f, 0.05f}), pm);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(st[i], mp.sigma_a[i] + mp.sigma_s[i], 1e-4f);
  const auto region = m.grid_region();
  ASSERT_TRUE(region);
  EXPECT_EQ(region->index_bounds.lo.x, -0.5f);
  EXPECT_EQ(region->index_bounds.hi.x, 15.5f);
}

TEST(Medium, MajorantBoundsEveryLaneOnRandomPoints) {
  const auto grid = ramp_grid();
  MediumDesc d;
  d.solvent = Solvent::water(Spectrum::constant(0.1f), Spectrum::constant(1.337f));
  d.pigments.push_back({ramp_pigment(), Field::from_grid(grid, 1e-6f)});
  d.majorant_voxels_per_cell = 4;
  const Medium m(d);
  const PreparedMedium pm = prepare(m, four_wavelengths());
  Rng rng(1, 0);
  for (int i = 0; i < 2000; ++i) {
    const Ray world{{rng.uniform() * 0.2f - 0.03f, rng.uniform() * 0.3f, rng.uniform() * 0.16f},
                    normalize(Vec3{rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f})};
    const Ray r = m.index_ray(world);
    auto it = m.majorants(r, 0.5f);
    while (auto s = it.next()) {
      const SampledSpectrum hi = pm.sigma_maj(*s, m.channels()), lo = pm.sigma_min(*s, m.channels());
      for (int k = 0; k < 8; ++k) {
        const SampledSpectrum st = m.sigma_t(r.at(s->t_min + rng.uniform() * (s->t_max - s->t_min)), pm);
        for (int l = 0; l < 4; ++l) {
          ASSERT_LE(st[l], hi[l] * (1.f + 1e-6f));
          ASSERT_GE(st[l], lo[l] * (1.f - 1e-6f));
        }
      }
    }
  }
}

TEST(Medium, InvalidDescriptionsAreRefused) {
  MediumDesc d;
  d.where = "scene.json: media.m";
  d.pigments.assign(5, {ramp_pigment(), Field::constant(1e-6f)});
  EXPECT_THROW(Medium{d}, InputError);
  d.pigments.resize(1);
  d.pigments[0].concentration = Field::constant(-1.f);
  try {
    Medium{d};
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pigments[0].concentration"), std::string::npos) << e.what();
  }
  d.pigments[0].concentration = Field::constant(1e-6f);
  d.particle_phase = HenyeyGreenstein{1.f};
  EXPECT_THROW(Medium{d}, InputError);
  d.particle_phase = HenyeyGreenstein{0.5f};
  d.solvent = Solvent::water(Spectrum::constant(0.1f), Spectrum{});  // index of refraction missing
  EXPECT_THROW(Medium{d}, InputError);
}
