// Heavier stress renders (label "long"): more pixels and samples, so the energy
// bound is checked with less Monte Carlo slack, and the costliest inputs of the
// CI-sized suite pushed further.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

#include "grids/vdb_file.h"
#include "stress_util.h"

using namespace chlorovdb;
using namespace chlorovdb::stress;

// More pixels, wavelengths and depth than the CI-sized suite's dye cube.
constexpr DyeCubeRender kLongRender{32, 8, 32};

TEST(StressLong, DefaultSceneWithinEnergyBound) {
  RenderCase c;
  c.name = "default_scene";
  std::ifstream in(std::string(CHLOROVDB_SOURCE_DIR) + "/scenes/default.json");
  c.json.assign(std::istreambuf_iterator<char>(in), {});
  c.overrides.width = 64;
  c.overrides.height = 48;
  c.spp = 32;
  c.threads = 2;
  c.seconds = 300;
  c.pixel_noise_factor = 2;
  render_case(c);
}

TEST(StressLong, OpticalDepth1e6GridEveryEstimator) {
  DenseGrid g({8, 8, 8});
  for (int z = 0; z < 8; ++z)
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x) g.at(x, y, z) = (x + y + z) % 2 ? float(2e6 / kSigmaPerMolar) : 0.f;
  g.world_from_index = Transform::translate(Vec3(-0.4375f)) * Transform::scale(Vec3(0.125f));
  g.metadata.name = "density";
  const auto path = scratch_dir() / "long_tau1e6.vdb";
  write_concentration_grid(path, g);
  // Today ratio and residual ratio tracking cost ~20-50 ms per camera path here (docs/robustness.md F8).
  for (const std::string estimator : {"auto", "ratio", "residual_ratio", "delta"}) {
    RenderCase c;
    c.name = "long_tau1e6_grid_" + estimator;
    c.json = dye_cube("\"grid\": {\"file\": \"" + path.string() + "\", \"unit\": \"M\"}", 1.0, "full", "", kLongRender);
    c.overrides.transmittance = estimator;
    c.overrides.width = c.overrides.height = 16;
    c.spp = 4;
    c.threads = 2;
    c.seconds = 120;
    try_case(c);
  }
}

TEST(StressLong, DenseScatteringReabsorptionCascade) {
  // Today this cascade grows exponentially with the scattering depth (docs/robustness.md F7).
  for (double tau_s : {100.0, 1000.0}) {
    RenderCase c;
    c.name = "long_scattering_reabsorption_" + num(tau_s);
    c.json = dye_cube("\"concentration\": " + num(1.0 / kSigmaPerMolar) + ", \"unit\": \"M\"", 1.0, "full",
                      ", \"scattering\": {\"coefficient\": " + num(tau_s) + ", \"g\": 0}", kLongRender);
    c.spp = 8;
    c.threads = 2;
    c.seconds = 120;
    try_case(c);
  }
}
