// Fluorescence events in a grid medium whose pigment fills a thin shell of a
// large box (the leaf): where the event point is drawn, and that the estimate
// stays exact.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "grids/vdb_file.h"
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
Scene shell_scene() {
  DenseGrid g({4, 4, kDepthVoxels});
  g.world_from_index = Transform::translate(Vec3(float(-1.5 * kVoxel), float(-1.5 * kVoxel), float(0.5 * kVoxel))) *
                       Transform::scale(Vec3(float(kVoxel)));
  g.metadata.name = "concentration";
  g.metadata.unit = "uM";
  for (int k = kShellFirst; k < kShellFirst + kShellVoxels; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) g.at(i, j, k) = float(kShellMicromolar);
  const auto dir = scratch_dir("integrator_tests");
  write_concentration_grid(dir / "thin_shell.vdb", g);
  char json[2048];
  std::snprintf(json, sizeof json, R"({
  "render": {"resolution": [8, 8], "spp": 1, "wavelengths": 4, "fluorescence": "direct"},
  "camera": {"type": "orthographic", "position": [0, 0, 1], "look_at": [0, 0, 0], "height": 0.002},
  "pigments": {"dye": {
    "extinction": {"table": {"lambda": [379.999, 380, 480, 480.001], "value": [0, 20000, 20000, 0]}},
    "quantum_yield": 0.5, "emission": {"gaussian": [650, 10]}}},
  "materials": {"boundary": {"type": "interface"}},
  "media": {"leaf": {"solvent": "none",
    "pigments": [{"pigment": "dye", "grid": {"file": "thin_shell.vdb", "name": "concentration", "unit": "uM"}}]}},
  "shapes": [{"type": "box", "min": [-0.002, -0.002, 0], "max": [0.002, 0.002, %g],
              "material": "boundary", "inside": "leaf"}],
  "lights": [{"type": "distant", "direction": [0, 0, -1], "spectrum": {"gaussian": [420, 8]}, "scale": 1}]
})",
                kDepthVoxels * kVoxel);
  return load_scene(write_scene("thin_shell", json));
}

}  // namespace

TEST(FluorescenceGrid, ThinShellEventsLandOnThePigmentAndStayExact) {
  const Scene scene = shell_scene();
  ASSERT_EQ(scene.fluorescence.size(), 1u);
  ASSERT_EQ(scene.fluorescence[0].size(), 1u);
  const FluorescentPigment& fp = scene.fluorescence[0][0];
  // Exact: nothing absorbs where the dye emits, so on the lit side
  // L(λ) = Q f(λ) / (4π λ) (1 - e^{-k ε C}) ∫ λ' E(λ') dλ', C the column density.
  const double column = kShellVoxels * kShellMicromolar * 1e-6 * kVoxel;  // mol/L · m
  const double absorbed = -std::expm1(-double(kAbsorptionPerMolarExtinction) * 20000 * column);
  const Spectrum& E = emission_spectrum(scene.lights[0]);
  double photon_flux = 0;
  for (double l = 380; l <= 480; l += 0.01) photon_flux += l * E(float(l)) * 0.01;

  std::array<Estimate, 4> e;
  PathStats stats;
  const float pdf[4] = {1, 1, 1, 1};
  const int paths = 20000;
  for (int i = 0; i < paths; ++i) {
    Rng rng(test_seed(61), uint64_t(i));
    SampledWavelengths lambda = SampledWavelengths::from_values(kLambdas, pdf, 4);
    const PathRadiance L = trace_path(scene, Ray{{0, 0, 1}, {0, 0, -1}}, scene.camera_medium, lambda, rng, stats);
    for (int k = 0; k < 4; ++k) e[k].add(L.fluorescence[k]);
  }
  for (int k = 0; k < 4; ++k) {
    const double exact = fp.quantum_yield * fp.emission(kLambdas[k]) * kInv4Pi / kLambdas[k] * absorbed * photon_flux;
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
