// Stress: concentrations from 1e-12 M to 1 M, optical depths up to 1e6 (homogeneous
// and grid media, every transmittance estimator), Q = 0 and Q = 1, absorption
// overlapping emission, and fluorescence inside a scattering medium.
#include <gtest/gtest.h>

#include "grids/vdb_file.h"
#include "stress_util.h"

using namespace chlorovdb;
using namespace chlorovdb::stress;

namespace {

std::string homogeneous_field(double molar) { return "\"concentration\": " + num(molar) + ", \"unit\": \"M\""; }

// 8^3 checkerboard (0 / c_max) filling the cube: trilinear lookups vary between
// 0 and c_max, so every estimator meets null collisions and majorant cells.
std::string checkerboard_grid_field(const std::string& name, double c_max) {
  DenseGrid g({8, 8, 8});
  for (int z = 0; z < 8; ++z)
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x) g.at(x, y, z) = (x + y + z) % 2 ? float(c_max) : 0.f;
  g.world_from_index = Transform::translate(Vec3(-0.4375f)) * Transform::scale(Vec3(0.125f));
  g.metadata.name = "density";
  g.metadata.unit = "M";
  const auto path = scratch_dir() / (name + ".vdb");
  write_concentration_grid(path, g);
  return "\"grid\": {\"file\": \"" + path.string() + "\", \"name\": \"density\", \"unit\": \"M\"}";
}

std::string sanitize(std::string s) {
  for (char& ch : s)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return s;
}

}  // namespace

// ---------------------------------------------------------------------------
// Chlorophyll a in water from 1e-12 M to 1 M (μ_a up to ~2e7 /m at the red peak)
// in a glass cuvette under white sky and a UVB panel, every fluorescence estimator.
// ---------------------------------------------------------------------------
void concentration_sweep(const std::string& mode) {
  for (double molar : {1e-12, 1e-9, 1e-6, 1e-3, 1.0}) {
    RenderCase c;
    c.name = "concentration_" + sanitize(num(molar)) + "M_" + mode;
    c.json = subst(R"({
      "length_unit": "cm",
      "render": {"resolution": [8, 8], "wavelengths": 4, "fluorescence": "$MODE"},
      "camera": {"position": [0, 4, 14], "look_at": [0, 2, 0], "fov": 30},
      "pigments": {"chl": {"extinction": "chlorophyll_a", "quantum_yield": 0.23}},
      "materials": {"floor": {"type": "diffuse", "albedo": 0.5}, "glass": {"type": "dielectric", "ior": 1.5},
                    "glass_to_solution": {"type": "dielectric", "ior": 0.8913}},
      "media": {"solution": {"solvent": "water", "pigments": [{"pigment": "chl", "concentration": $C, "unit": "M"}]}},
      "shapes": [
        {"type": "quad", "corner": [-20, 0, -20], "edge_u": [0, 0, 40], "edge_v": [40, 0, 0], "material": "floor"},
        {"type": "box", "min": [-2.2, 0.001, -2.2], "max": [2.2, 4.4, 2.2], "material": "glass"},
        {"type": "box", "min": [-2, 0.2, -2], "max": [2, 4.2, 2], "material": "glass_to_solution", "inside": "solution"},
        {"type": "quad", "corner": [-10, 1, -3], "edge_u": [0, 6, 0], "edge_v": [0, 0, 6],
         "emission": {"spectrum": "UVB", "scale": 5}}],
      "lights": [{"type": "environment", "spectrum": "D65", "scale": 0.01}]
    })",
                   {{"$MODE", mode}, {"$C", num(molar)}});
    try_case(c);
  }
}

TEST(Stress, ConcentrationSweepFull) { concentration_sweep("full"); }
TEST(Stress, ConcentrationSweepDirect) { concentration_sweep("direct"); }
TEST(Stress, ConcentrationSweepReference) { concentration_sweep("reference"); }

// ---------------------------------------------------------------------------
// Optical depth across the 1 m cube from 1e-3 to 1e6, homogeneous and grid,
// with every transmittance estimator (auto = closed form / residual ratio).
// Grid, τ = 1e6, ratio and residual ratio: in long/ (seconds each today, finding F8).
// ---------------------------------------------------------------------------
void optical_depth(bool grid, const std::string& estimator, std::initializer_list<double> taus) {
  for (double tau : taus) {
    RenderCase c;
    c.name = std::string("tau_") + sanitize(num(tau)) + (grid ? "_grid_" : "_homogeneous_") + estimator;
    // Homogeneous: τ = σ·c·1 m. Checkerboard: c_max = 2·(mean), so τ ≈ σ·c_max/2 along a ray.
    const double molar = tau / kSigmaPerMolar;
    const std::string field = grid ? checkerboard_grid_field(c.name, 2 * molar) : homogeneous_field(molar);
    c.json = dye_cube(field, 0.5, "full");
    c.overrides.transmittance = estimator;
    c.spp = 4;
    c.seconds = 10;
    try_case(c);
  }
}

TEST(Stress, OpticalDepthHomogeneousEveryEstimator) {
  for (const std::string e : {"auto", "ratio", "residual_ratio", "delta"}) optical_depth(false, e, {1e-3, 1, 1e3, 1e6});
}
TEST(Stress, OpticalDepthGridDelta) { optical_depth(true, "delta", {1e-3, 1, 1e3, 1e6}); }
TEST(Stress, OpticalDepthGridRatio) { optical_depth(true, "ratio", {1e-3, 1, 1e3}); }
TEST(Stress, OpticalDepthGridResidualRatio) { optical_depth(true, "residual_ratio", {1e-3, 1, 1e3}); }
TEST(Stress, OpticalDepthGridAuto) { optical_depth(true, "auto", {1e-3, 1, 1e3}); }

// ---------------------------------------------------------------------------
// Quantum yield at its limits.
// ---------------------------------------------------------------------------

// Q = 0: docs/physics.md §7 "Q = 0 gives exactly zero fluorescence", in every mode.
TEST(Stress, QuantumYieldZeroGivesExactlyZeroFluorescence) {
  for (const std::string mode : {"auto", "direct", "full", "reference", "off"}) {
    RenderCase c;
    c.name = "q0_" + mode;
    c.json = dye_cube(homogeneous_field(1.0 / kSigmaPerMolar), 0.0, mode);
    if (const auto o = try_case(c)) {
      EXPECT_EQ(layer_sum(*o, kLayerFluorescence), 0.0) << c.name;
      EXPECT_GT(layer_sum(*o, kLayerTotal), 0.0) << c.name;
    }
  }
}

// Q = 1 with a dye that absorbs its own emission (every emitted photon can be
// reabsorbed and re-emitted): optically thin, thick and very thick.
void quantum_yield_one(const std::string& mode) {
  for (double tau : {0.1, 10.0, 1e4}) {
    RenderCase c;
    c.name = "q1_tau" + sanitize(num(tau)) + "_" + mode;
    c.json = dye_cube(homogeneous_field(tau / kSigmaPerMolar), 1.0, mode);
    c.seconds = 10;
    if (const auto o = try_case(c)) EXPECT_GT(layer_sum(*o, kLayerFluorescence), 0.0) << c.name << ": no fluorescence";
  }
}

TEST(Stress, QuantumYieldOneDirect) { quantum_yield_one("direct"); }
TEST(Stress, QuantumYieldOneFull) { quantum_yield_one("full"); }
TEST(Stress, QuantumYieldOneReference) { quantum_yield_one("reference"); }

// ---------------------------------------------------------------------------
// Emission inside the absorption band of a scattering medium, full mode: every
// segment of every excitation continuation can start another continuation, so
// the cost is a branching process. It must stay bounded: 8x8 pixels, 4 spp.
// ---------------------------------------------------------------------------
TEST(Stress, ScatteringReabsorptionCascadeTerminates) {
  for (double tau_s : {1.0, 10.0, 30.0}) {
    RenderCase c;
    c.name = "scattering_reabsorption_taus" + sanitize(num(tau_s));
    c.json = dye_cube(homogeneous_field(1.0 / kSigmaPerMolar), 1.0, "full",
                      ", \"scattering\": {\"coefficient\": " + num(tau_s) + ", \"g\": 0}");
    c.spp = 4;
    c.seconds = 10;
    try_case(c);
  }
}

// Chlorophyll's own absorption spectrum used as its emission spectrum: the
// strongest possible overlap, with the measured extinction table.
TEST(Stress, EmissionEqualsAbsorptionSpectrum) {
  for (const std::string mode : {"direct", "full", "reference"}) {
    RenderCase c;
    c.name = "emission_equals_absorption_" + mode;
    c.json = subst(R"({
      "render": {"resolution": [8, 8], "wavelengths": 8, "fluorescence": "$MODE"},
      "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov": 30},
      "pigments": {"chl": {"extinction": "chlorophyll_a", "quantum_yield": 1, "emission": "chlorophyll_a"}},
      "materials": {"boundary": {"type": "interface"}},
      "media": {"s": {"solvent": "water", "pigments": [{"pigment": "chl", "concentration": 100, "unit": "uM"}]}},
      "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 0.5, "material": "boundary", "inside": "s"}],
      "lights": [{"type": "environment", "spectrum": 1}]
    })",
                   {{"$MODE", mode}});
    c.spectral_bins = 16;
    c.seconds = 10;
    try_case(c);
  }
}
