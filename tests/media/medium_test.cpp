#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/rng.h"
#include "media/medium.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

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
  // Voxels 0..15 hold data; a trilinear lookup is non-zero up to one voxel past
  // the outer centres, so the medium's box is [-1, 16] (grids/vdb_file.cpp).
  EXPECT_EQ(region->index_bounds.lo.x, -1.f);
  EXPECT_EQ(region->index_bounds.hi.x, 16.f);
}

TEST(Medium, ScatteringIsThePropertiesScatteringPart) {
  // A scattering event asks for MediumScattering alone: it must be what the full
  // MediumProperties say, with molecules (water) and particles (a grid) both scattering.
  const auto grid = ramp_grid();
  MediumDesc d;
  d.solvent = Solvent::water(Spectrum::constant(0.1f), Spectrum::constant(1.337f));
  d.pigments.push_back({ramp_pigment(), Field::from_grid(grid, 1e-6f)});
  d.particle_sigma_s = Field::from_grid(grid, 0.5f);
  d.particle_phase = HenyeyGreenstein{0.6f};
  const Medium m(d);
  const PreparedMedium pm = prepare(m, four_wavelengths());
  for (const Vec3 p_world : {Vec3{0.0725f, 0.1f, 0.05f}, Vec3{0.001f, 0.2f, 0.1f}, Vec3{0.5f, 0.5f, 0.5f}}) {
    const Medium::ChannelValues v = m.channel_values(m.index_point(p_world));
    const MediumProperties mp = m.properties(v, pm);
    const MediumScattering ms = m.scattering(v, pm);
    for (int i = 0; i < kMaxWavelengths; ++i) {
      EXPECT_EQ(ms.sigma_s[i], mp.sigma_s[i]);
      EXPECT_EQ(ms.phase.particle_fraction[i], mp.phase.particle_fraction[i]);
    }
    EXPECT_EQ(std::get<HenyeyGreenstein>(ms.phase.particle).g, 0.6f);
  }
}

TEST(Medium, MajorantBoundsEveryLaneOnRandomPoints) {
  const auto grid = ramp_grid();
  MediumDesc d;
  d.solvent = Solvent::water(Spectrum::constant(0.1f), Spectrum::constant(1.337f));
  d.pigments.push_back({ramp_pigment(), Field::from_grid(grid, 1e-6f)});
  d.majorant_voxels_per_cell = 4;
  const Medium m(d);
  const PreparedMedium pm = prepare(m, four_wavelengths());
  Rng rng(test_seed(1), 0);
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

namespace {

// A Gaussian blob of 32^3 voxels of 1 cm with scattering particles: sigma_s = scale * value.
Medium blob_medium(float scale, int voxels_per_cell = 0) {
  DenseGrid g({32, 32, 32});
  for (int z = 0; z < 32; ++z)
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x) {
        const float r2 = float((x - 16) * (x - 16) + (y - 16) * (y - 16) + (z - 16) * (z - 16));
        g.at(x, y, z) = std::exp(-r2 / (2.f * 5.f * 5.f));
      }
  g.world_from_index = Transform::scale({0.01f, 0.01f, 0.01f});
  MediumDesc d;
  d.particle_sigma_s = Field::from_grid(std::make_shared<const VoxelGrid>(VoxelGrid::from_dense(g)), scale);
  d.majorant_voxels_per_cell = voxels_per_cell;
  return Medium(d);
}

}  // namespace

// Thicker media get finer majorant cells: tighter bounds pay for their extra
// segments once collisions dominate (docs/performance.md, session 5).
TEST(Medium, MajorantCellsShrinkAsTheMediumThickens) {
  int previous = 1 << 30;
  for (const float scale : {1.f, 100.f, 1e4f, 1e6f}) {
    const int size = blob_medium(scale).majorant_grid().voxels_per_cell();
    EXPECT_NE(std::find(kMajorantCellSizes.begin(), kMajorantCellSizes.end(), size), kMajorantCellSizes.end());
    EXPECT_LE(size, previous) << "scale " << scale;
    previous = size;
  }
  // Thin: collisions are rare, segments dominate. Thick: the other way round.
  EXPECT_GE(blob_medium(1.f).majorant_grid().voxels_per_cell(), 12);
  EXPECT_EQ(blob_medium(1e6f).majorant_grid().voxels_per_cell(), kMajorantCellSizes.front());
  EXPECT_EQ(blob_medium(1e6f, 7).majorant_grid().voxels_per_cell(), 7);  // an explicit size is kept
  EXPECT_THROW(blob_medium(1.f, -1), InputError);
  // So thick that every candidate's modelled cost overflows to inf: a grid is still chosen.
  EXPECT_EQ(blob_medium(3e38f).majorant_grid().channels(), 1);
}

// tracking_cost on a uniform field: every non-empty cell costs its volume times
// (segment cost / mean chord + sigma_maj), the chord being 2/3 of the cell edge.
TEST(Medium, TrackingCostOfAUniformGrid) {
  DenseGrid g({8, 8, 8}, 0.5f);
  const VoxelGrid grid = VoxelGrid::from_dense(g);
  const VoxelGrid* grids[] = {&grid};
  const MajorantGrid m(grids, 4, Interpolation::trilinear);
  int non_empty = 0;
  for (int z = 0; z < m.resolution()[2]; ++z)
    for (int y = 0; y < m.resolution()[1]; ++y)
      for (int x = 0; x < m.resolution()[0]; ++x) non_empty += m.cell_max({x, y, z}, 0) > 0.f;
  const float sigma_per_value[] = {30.f};
  const double edge = 4 * 0.01, expected = non_empty * edge * edge * edge * (0.8 / (2.0 / 3.0 * edge) + 30.0 * 0.5);
  EXPECT_NEAR(m.tracking_cost(sigma_per_value, 0.01f, 0.8f), expected, 1e-6 * expected);  // 0.01f is not 0.01
}
