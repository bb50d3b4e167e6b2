// Fluorescence events in a grid medium whose pigment fills a thin shell of a
// large box (the leaf): where the event point is drawn, and that the estimate
// stays exact.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include <fmt/format.h>

#include "grids/vdb_file.h"
#include "integrator/excitation_photons.h"
#include "media/pigment.h"
#include "test_scenes.h"
#include "test_seed.h"

using namespace chlorovdb;
using namespace chlorovdb::test;

namespace {

constexpr float kLambdas[4] = {635.f, 650.f, 662.f, 675.f};
constexpr double kVoxel = 1e-3;    // m
constexpr int kDepthVoxels = 200;  // the box: 20 cm deep
constexpr int kShellFirst = 98, kShellVoxels = 4;  // pigment in 4 mm of it
constexpr double kShellMicromolar = 20;

// A 4 × 4 × 200 voxel grid, 1 mm voxels, zero but for a 4-voxel layer across the
// middle, inside an index-matched box exactly as deep, lit along -z by a
// distant light. Along the central ray trilinear lookups are the linear
// interpolation of the voxel column, so the pigment's column density is exactly
// Σ c_k · voxel.
//
// `render_extra` is added to the render settings. `sides_through_centres` narrows
// the box to the planes through the outermost voxels' centres, so half of their
// interpolated pigment lies outside the medium; `on_floor` moves the pigment to
// the bottom layers, centred on the box's floor, as a spill's sit on the floor.
struct ShellPlacement {
  bool sides_through_centres = false, on_floor = false;
};
Scene shell_scene(const std::string& render_extra = "", ShellPlacement place = {}) {
  DenseGrid g({4, 4, kDepthVoxels});
  g.world_from_index = Transform::translate(Vec3(float(-1.5 * kVoxel), float(-1.5 * kVoxel),
                                                 float((place.on_floor ? 0.0 : 0.5) * kVoxel))) *
                       Transform::scale(Vec3(float(kVoxel)));
  g.metadata.name = "concentration";
  g.metadata.unit = "uM";
  const int first = place.on_floor ? 0 : kShellFirst;
  for (int k = first; k < first + kShellVoxels; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) g.at(i, j, k) = float(kShellMicromolar);
  const auto dir = scratch_dir("integrator_tests");
  const std::string name =
      fmt::format("thin_shell{}{}", place.sides_through_centres ? "_narrow" : "", place.on_floor ? "_on_floor" : "");
  write_concentration_grid(dir / (name + ".vdb"), g);
  const double side = place.sides_through_centres ? 1.5 * kVoxel : 2 * kVoxel;
  char json[2048];
  std::snprintf(json, sizeof json, R"({
  "render": {"resolution": [8, 8], "spp": 1, "wavelengths": 4, "fluorescence": "direct"%s},
  "camera": {"type": "orthographic", "position": [0, 0, 1], "look_at": [0, 0, 0], "height": 0.002},
  "pigments": {"dye": {
    "extinction": {"table": {"lambda": [379.999, 380, 480, 480.001], "value": [0, 20000, 20000, 0]}},
    "quantum_yield": 0.5, "emission": {"gaussian": [650, 10]}}},
  "materials": {"boundary": {"type": "interface"}},
  "media": {"leaf": {"solvent": "none",
    "pigments": [{"pigment": "dye", "grid": {"file": "%s.vdb", "name": "concentration", "unit": "uM"}}]}},
  "shapes": [{"type": "box", "min": [%g, %g, 0], "max": [%g, %g, %g],
              "material": "boundary", "inside": "leaf"}],
  "lights": [{"type": "distant", "direction": [0, 0, -1], "spectrum": {"gaussian": [420, 8]}, "scale": 1}]
})",
                render_extra.c_str(), name.c_str(), -side, -side, side, side, kDepthVoxels * kVoxel);
  return load_scene(write_scene(name, json));
}

// The exact radiance of the lit side: nothing absorbs where the dye emits, so
// L(λ) = Q f(λ) / (4π λ) (1 - e^{-k ε C}) ∫ λ' E(λ') dλ', C the column density.
double shell_radiance(const Scene& scene, float lambda) {
  const FluorescentPigment& fp = scene.fluorescence[0][0];
  const double column = kShellVoxels * kShellMicromolar * 1e-6 * kVoxel;  // mol/L · m
  const double absorbed = -std::expm1(-double(kAbsorptionPerMolarExtinction) * 20000 * column);
  const Spectrum& E = emission_spectrum(scene.lights[0]);
  double photon_flux = 0;
  for (double l = 380; l <= 480; l += 0.01) photon_flux += l * E(float(l)) * 0.01;
  return fp.quantum_yield * fp.emission(lambda) * kInv4Pi / lambda * absorbed * photon_flux;
}

// The central ray's fluorescence at the four wavelengths over `paths` paths.
std::array<Estimate, 4> shell_estimates(const Scene& scene, int paths, uint64_t seed, PathStats& stats) {
  std::array<Estimate, 4> e;
  const float pdf[4] = {1, 1, 1, 1};
  for (int i = 0; i < paths; ++i) {
    Rng rng(seed, uint64_t(i));
    SampledWavelengths lambda = SampledWavelengths::from_values(kLambdas, pdf, 4);
    const PathRadiance L = trace_path(scene, Ray{{0, 0, 1}, {0, 0, -1}}, scene.camera_medium, lambda, rng, stats);
    for (int k = 0; k < 4; ++k) e[k].add(L.fluorescence[k]);
  }
  return e;
}

}  // namespace

TEST(FluorescenceGrid, ThinShellEventsLandOnThePigmentAndStayExact) {
  const Scene scene = shell_scene();
  ASSERT_EQ(scene.fluorescence.size(), 1u);
  ASSERT_EQ(scene.fluorescence[0].size(), 1u);
  PathStats stats;
  const std::array<Estimate, 4> e = shell_estimates(scene, 20000, test_seed(61), stats);
  for (int k = 0; k < 4; ++k) {
    const double exact = shell_radiance(scene, kLambdas[k]);
    EXPECT_NEAR(e[k].mean(), exact, 4 * e[k].sigma())
        << "λ=" << kLambdas[k] << " rel.err " << e[k].mean() / exact - 1 << " (σ/mean " << e[k].sigma() / exact << ")";
  }
  // Drawn along the box (no attenuation at the emitted wavelengths, so
  // uniformly), a point would find pigment only where lookups reach the layer:
  // 5 voxels of 200, 2.5 %. Drawn per majorant cell, the share is that of the
  // layer in the cells holding it: at least four times more.
  ASSERT_GT(stats.fluorescence_points, 0u);
  const double useful = double(stats.fluorescence_events) / double(stats.fluorescence_points);
  const double useful_along_box = double(kShellVoxels + 1) / kDepthVoxels;
  std::printf("thin shell: %.1f %% of event points find pigment (%.1f %% if drawn along the box)\n", 100 * useful,
              100 * useful_along_box);
  EXPECT_GT(useful, 4 * useful_along_box);
}

// Photons (render.excitation_estimate = photons) in the same shell (its box's
// sides through the outer voxels' centres, where the pigment amount is exact): two
// photon cells 10 cm deep, the pigment 4 mm of them, straddling their face, and
// the light falls by a third across it. The tallies weighted by concentration read
// the fluence inside the pigment, and the central ray, on the corner of four cells,
// gets the exact radiance within 4σ of its own noise and the grid's (its reported
// per-cell error: a pixel's error from the grid is at most that).
TEST(FluorescenceGrid, ThinShellPhotonsGiveTheExactRadiance) {
  const Scene scene = shell_scene(
      R"(, "excitation_estimate": "photons", "excitation_photons": 8388608, "excitation_photons_aimed": 0.99,)"
      R"( "excitation_grid_cells": 2)",
      {.sides_through_centres = true});
  prepare_excitation_grids(scene, test_seed(62));
  const ExcitationGrid* grid = scene.excitation_grid(0, 0);
  ASSERT_NE(grid, nullptr);
  EXPECT_EQ(grid->measure(), ExcitationGrid::Measure::amount);
  PathStats stats;
  const std::array<Estimate, 4> e = shell_estimates(scene, 20000, test_seed(63), stats);
  for (int k = 0; k < 4; ++k) {
    const double exact = shell_radiance(scene, kLambdas[k]);
    const double grid_sigma = grid->relative_error() * exact;
    std::printf("thin shell, photons: λ=%.0f rel.err %+.4f (σ/mean %.4f, grid %.4f)\n", kLambdas[k], e[k].mean() / exact - 1,
                e[k].sigma() / exact, grid->relative_error());
    EXPECT_NEAR(e[k].mean(), exact, 4 * std::hypot(e[k].sigma(), grid_sigma))
        << "λ=" << kLambdas[k] << " rel.err " << e[k].mean() / exact - 1 << " (σ/mean " << e[k].sigma() / exact
        << ", grid " << grid->relative_error() << ")";
  }
}

// The photon cells' pigment is the interpolated concentration inside the medium
// only: with the box's floor and sides through the centres of the pigment's
// outermost voxels (a spill's bottom layer sits on the floor) the half of their
// tents outside the box holds no pigment a photon or an event can meet. The cells
// hold 20 µM × 3 mm × 3 mm × 3.5 voxels; counted whole at the voxels' centres
// (where the floor is) a layer went missing or the fringes were added.
TEST(FluorescenceGrid, PhotonCellsHoldOnlyThePigmentInsideTheMedium) {
  const Scene scene = shell_scene(R"(, "excitation_estimate": "photons", "excitation_photons": 1024)",
                                  {.sides_through_centres = true, .on_floor = true});
  prepare_excitation_grids(scene, test_seed(64));
  const ExcitationGrid* grid = scene.excitation_grid(0, 0);
  ASSERT_NE(grid, nullptr);
  double amount = 0;
  for (size_t c = 0; c < grid->cell_count(); ++c) amount += grid->medium_measure(c);
  const double expected = kShellMicromolar * 1e-6 * (3 * kVoxel) * (3 * kVoxel) * (kShellVoxels - 0.5) * kVoxel;
  EXPECT_NEAR(amount / expected, 1.0, 1e-4);
}

// A grid whose axes are not the world's (8³ voxels of 20 µM turned 30° about z and
// 20° about x, in the box the loader puts around it): its voxels go to the photon
// cells as octants, and the cells hold all of its pigment, Σ c · voxel volume.
TEST(FluorescenceGrid, PhotonCellsHoldARotatedGridsPigment) {
  DenseGrid g({8, 8, 8}, float(kShellMicromolar));
  g.world_from_index = Transform::rotate(30.f, {0, 0, 1}) * Transform::rotate(20.f, {1, 0, 0}) *
                       Transform::scale(Vec3(float(kVoxel)));
  g.metadata.name = "concentration";
  g.metadata.unit = "uM";
  write_concentration_grid(scratch_dir("integrator_tests") / "rotated_block.vdb", g);
  const Scene scene = load_scene(write_scene("rotated_block", R"({
  "render": {"resolution": [8, 8], "spp": 1, "wavelengths": 4, "fluorescence": "direct",
             "excitation_estimate": "photons", "excitation_photons": 1024},
  "camera": {"type": "orthographic", "position": [0, 0, 1], "look_at": [0, 0, 0], "height": 0.02},
  "pigments": {"dye": {
    "extinction": {"table": {"lambda": [379.999, 380, 480, 480.001], "value": [0, 20000, 20000, 0]}},
    "quantum_yield": 0.5, "emission": {"gaussian": [650, 10]}}},
  "media": {"block": {"solvent": "none",
    "pigments": [{"pigment": "dye", "grid": {"file": "rotated_block.vdb", "name": "concentration", "unit": "uM"}}]}},
  "lights": [{"type": "distant", "direction": [0, 0, -1], "spectrum": {"gaussian": [420, 8]}, "scale": 1}]
})"));
  prepare_excitation_grids(scene, test_seed(65));
  const ExcitationGrid* grid = scene.excitation_grid(0, 0);
  ASSERT_NE(grid, nullptr);
  double amount = 0;
  for (size_t c = 0; c < grid->cell_count(); ++c) amount += grid->medium_measure(c);
  const double expected = kShellMicromolar * 1e-6 * 512 * kVoxel * kVoxel * kVoxel;
  EXPECT_NEAR(amount / expected, 1.0, 1e-4);
}
