// docs/physics.md §7: the analytic slab, photon balance, Q = 0, direct vs full, photon tallies.
#include <gtest/gtest.h>

#include "core/error.h"
#include "integrator/excitation_photons.h"
#include "media/pigment.h"
#include "spectra/library.h"
#include "test_scenes.h"
#include "test_seed.h"

using namespace chlorovdb;
using namespace chlorovdb::test;

namespace {

constexpr float kEmissionLambdas[4] = {635.f, 650.f, 662.f, 675.f};

struct SlabTruth {
  const Scene& scene;
  const SlabSetup& setup;
  double solvent_absorption;  // 1/m, flat

  double mu_pigment(double lambda) const {
    const FluorescentPigment& fp = scene.fluorescence[0][0];
    return kAbsorptionPerMolarExtinction * fp.epsilon(float(lambda)) * setup.concentration * 1e-6;
  }
  // L(λ) of docs/physics.md §7 for the reflection side (camera on the lit face) or
  // the transmission side, integrating over λ' numerically.
  double radiance(double lambda, bool reflection_side) const {
    const FluorescentPigment& fp = scene.fluorescence[0][0];
    const Spectrum& E = emission_spectrum(scene.lights[0]);
    const double mu_l = solvent_absorption;  // the pigment does not absorb where it emits
    const double D = setup.D;
    double integral = 0;
    const double step = 0.02;
    for (double lp = setup.eps_lo; lp <= setup.eps_hi; lp += step) {
      const double mu_a = mu_pigment(lp), mu_lp = mu_a + solvent_absorption;
      const double G = reflection_side ? -std::expm1(-(mu_l + mu_lp) * D) / (mu_l + mu_lp)
                                       : (std::exp(-mu_lp * D) - std::exp(-mu_l * D)) / (mu_l - mu_lp);
      integral += (lp / lambda) * mu_a * E(float(lp)) * G * step;
    }
    return fp.quantum_yield * fp.emission(float(lambda)) * kInv4Pi * integral;
  }
};

// Mean fluorescence radiance per lane along one camera ray through the slab centre.
std::array<Estimate, 4> measure(const Scene& scene, Ray ray, int paths, uint64_t seed) {
  std::array<Estimate, 4> e;
  const float pdf[4] = {1, 1, 1, 1};
  PathStats stats;
  for (int i = 0; i < paths; ++i) {
    Rng rng(test_seed(seed), uint64_t(i));
    SampledWavelengths lambda = SampledWavelengths::from_values(kEmissionLambdas, pdf, 4);
    const PathRadiance L = trace_path(scene, ray, scene.camera_medium, lambda, rng, stats);
    EXPECT_TRUE(L.other.is_black());
    for (int k = 0; k < 4; ++k) e[k].add(L.fluorescence[k]);
  }
  return e;
}

Scene slab_scene(const SlabSetup& s, const std::string& name, double solvent_absorption) {
  std::string json = slab_scene_json(s);
  if (solvent_absorption > 0) {
    const std::string from = "\"solvent\": \"none\"";
    json.replace(json.find(from), from.size(),
                 "\"solvent\": {\"absorption\": " + std::to_string(solvent_absorption) + ", \"rayleigh\": false}");
  }
  return load_scene(write_scene(name, json));
}

void check_slab(const SlabSetup& s, const std::string& name, double solvent, bool reflection_side, int paths) {
  const Scene scene = slab_scene(s, name, solvent);
  ASSERT_EQ(scene.fluorescence.size(), 1u);
  ASSERT_EQ(scene.fluorescence[0].size(), 1u);
  const SlabTruth truth{scene, s, solvent};
  const Ray ray = reflection_side ? Ray{{0, 0, 1}, {0, 0, -1}} : Ray{{0, 0, -1}, {0, 0, 1}};
  const auto e = measure(scene, ray, paths, 17);
  for (int k = 0; k < 4; ++k) {
    const double exact = truth.radiance(kEmissionLambdas[k], reflection_side);
    ASSERT_GT(exact, 0.0);
    EXPECT_NEAR(e[k].mean(), exact, 4 * e[k].sigma() + 1e-6 * exact)
        << name << " λ=" << kEmissionLambdas[k] << " rel.err " << (e[k].mean() / exact - 1) << " (σ/mean "
        << e[k].sigma() / exact << ")";
  }
}

}  // namespace

TEST(FluorescenceSlab, NarrowBandReflectionSide) {
  SlabSetup s;
  check_slab(s, "slab_narrow_refl", 30.0, true, 20000);
}

TEST(FluorescenceSlab, NarrowBandTransmissionSide) {
  SlabSetup s;
  check_slab(s, "slab_narrow_trans", 30.0, false, 20000);
}

TEST(FluorescenceSlab, BroadBandD65BothSidesSeveralThicknesses) {
  for (double D : {0.002, 0.01, 0.05}) {
    SlabSetup s;
    s.D = D;
    s.light = "\"D65\"";
    check_slab(s, "slab_d65_refl", 10.0, true, 12000);
    check_slab(s, "slab_d65_trans", 10.0, false, 12000);
  }
}

TEST(FluorescenceSlab, StokesRedistributionMatchesKashaWhenExcitationIsBluer) {
  // All excitation (380–480 nm) lies below the emission band, so the Stokes
  // weight 1/F(λ') is 1 and both choices give the same image.
  SlabSetup s;
  std::string json = slab_scene_json(s);
  json.replace(json.find("\"quantum_yield\""), 0, "\"redistribution\": \"stokes\", ");
  const Scene stokes = load_scene(write_scene("slab_stokes", json));
  const SlabTruth truth{stokes, s, 0.0};
  const auto e = measure(stokes, Ray{{0, 0, 1}, {0, 0, -1}}, 20000, 5);
  for (int k = 0; k < 4; ++k)
    EXPECT_NEAR(e[k].mean(), truth.radiance(kEmissionLambdas[k], true), 4 * e[k].sigma());
}

TEST(FluorescenceSlab, FullAgreesWithDirectWhereDirectIsExact) {
  SlabSetup direct;
  SlabSetup full = direct;
  full.mode = "full";
  const Scene a = slab_scene(direct, "slab_direct", 0.0);
  const Scene b = slab_scene(full, "slab_full", 0.0);
  const auto ea = measure(a, Ray{{0, 0, 1}, {0, 0, -1}}, 20000, 3);
  const auto eb = measure(b, Ray{{0, 0, 1}, {0, 0, -1}}, 20000, 4);
  for (int k = 0; k < 4; ++k) {
    const double sigma = std::hypot(ea[k].sigma(), eb[k].sigma());
    EXPECT_NEAR(ea[k].mean(), eb[k].mean(), 4 * sigma);
  }
}

TEST(FluorescenceSlab, AutoPicksDirectWhenExactAndFullWhenNot) {
  SlabSetup s;
  s.mode = "auto";
  const Scene exact = slab_scene(s, "slab_auto", 0.0);
  EXPECT_EQ(exact.settings.fluorescence, FluorescenceMode::direct);
  std::string json = slab_scene_json(s);
  json.replace(json.find("\"solvent\": \"none\""), std::string("\"solvent\": \"none\"").size(), "\"solvent\": \"water\"");
  const Scene scattering = load_scene(write_scene("slab_auto_water", json));
  EXPECT_EQ(scattering.settings.fluorescence, FluorescenceMode::full);
  EXPECT_NE(scattering.settings.fluorescence_reason.find("scatters"), std::string::npos);
}

TEST(FluorescenceSlab, ZeroQuantumYieldGivesExactlyZeroFluorescence) {
  SlabSetup s;
  s.Q = 0.0;
  const Scene scene = slab_scene(s, "slab_q0", 0.0);
  EXPECT_FALSE(scene.has_fluorescence());
  const auto e = measure(scene, Ray{{0, 0, 1}, {0, 0, -1}}, 2000, 1);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(e[k].sum, 0.0);
}

TEST(FluorescenceSlab, PhotonBalanceWithUnitQuantumYield) {
  // Emitted photons (both faces, all directions) = absorbed photons, since Q = 1
  // and nothing absorbs in the emission band.
  SlabSetup s;
  s.Q = 1.0;
  const Scene scene = slab_scene(s, "slab_photons", 0.0);
  const SlabTruth truth{scene, s, 0.0};
  const Spectrum& E = emission_spectrum(scene.lights[0]);
  double absorbed = 0;  // photons per area, in units of 1/(hc): ∫ E λ' (1 − e^{−μ'D}) dλ'
  for (double lp = s.eps_lo; lp <= s.eps_hi; lp += 0.01)
    absorbed += E(float(lp)) * lp * -std::expm1(-truth.mu_pigment(lp) * s.D) * 0.01;

  Estimate emitted;  // photons per area leaving both faces: 2π E[L λ / pdf(λ)]
  PathStats stats;
  for (int i = 0; i < 60000; ++i) {
    Rng rng(test_seed(99), uint64_t(i));
    const bool top = rng.uniform() < 0.5f;
    const Vec3 n = top ? Vec3{0, 0, 1} : Vec3{0, 0, -1};
    const Vec3 local = sample_cosine_hemisphere({rng.uniform(), rng.uniform()});
    const Vec3 w = Frame::from_z(n).to_world(local);
    const Vec3 x0 = top ? Vec3{0, 0, float(s.D)} : Vec3{0, 0, 0};
    SampledWavelengths lambda = SampledWavelengths::sample_uniform(rng.uniform(), 4, 590.f, 710.f);
    const PathRadiance L = trace_path(scene, Ray{x0 + w, -w}, -1, lambda, rng, stats);
    double photons = 0;
    for (int k = 0; k < 4; ++k) photons += L.fluorescence[k] * lambda[k] / lambda.pdf(k) / 4;
    emitted.add(2 * kPi * photons);  // π for the cosine pdf, 2 for the side choice
  }
  EXPECT_NEAR(emitted.mean(), absorbed, 4 * emitted.sigma() + 0.005 * absorbed)
      << "emitted/absorbed = " << emitted.mean() / absorbed << " ± " << emitted.sigma() / absorbed;
}

// render.excitation_sampling and render.quantum_yield_mode (docs/fluorescence.md):
// every value must leave the estimator unbiased, in direct and full mode.
constexpr const char* kUniformExcitation = R"(, "excitation_sampling": "uniform")";
constexpr const char* kQRoulette = R"(, "quantum_yield_mode": "roulette")";

TEST(FluorescenceSlab, SwitchesAreReadIntoTheSettings) {
  SlabSetup s;
  const Scene defaults = slab_scene(s, "slab_switch_defaults", 0.0);
  EXPECT_EQ(defaults.settings.excitation_sampling, ExcitationSampling::importance);
  EXPECT_EQ(defaults.settings.quantum_yield_mode, QuantumYieldMode::weight);
  EXPECT_EQ(defaults.fluorescence[0][0].excitation[0].mode(), ExcitationSampling::importance);
  s.render_extra = std::string(kUniformExcitation) + kQRoulette;
  const Scene both = slab_scene(s, "slab_switch_both", 0.0);
  EXPECT_EQ(both.settings.excitation_sampling, ExcitationSampling::uniform);
  EXPECT_EQ(both.settings.quantum_yield_mode, QuantumYieldMode::roulette);
  EXPECT_EQ(both.fluorescence[0][0].excitation[0].mode(), ExcitationSampling::uniform);
}

TEST(FluorescenceSlab, UniformExcitationSamplingNarrowBandBothSides) {
  SlabSetup s;
  s.render_extra = kUniformExcitation;
  check_slab(s, "slab_uniform_refl", 30.0, true, 20000);
  check_slab(s, "slab_uniform_trans", 30.0, false, 20000);
}

TEST(FluorescenceSlab, UniformExcitationSamplingBroadBandD65) {
  // Over a broad light the uniform λ' differs most from S·ε·λ'.
  SlabSetup s;
  s.light = "\"D65\"";
  s.render_extra = kUniformExcitation;
  check_slab(s, "slab_uniform_d65_refl", 10.0, true, 12000);
  check_slab(s, "slab_uniform_d65_trans", 10.0, false, 12000);
}

TEST(FluorescenceSlab, QuantumYieldRouletteNarrowBandBothSides) {
  SlabSetup s;
  s.render_extra = kQRoulette;
  check_slab(s, "slab_roulette_refl", 30.0, true, 20000);
  check_slab(s, "slab_roulette_trans", 30.0, false, 20000);
  s.Q = 1.0;  // always passes: the weight mode's estimate, plus one unused random number
  check_slab(s, "slab_roulette_q1", 30.0, true, 20000);
  s.Q = 0.1;  // rarely passes, at weight 1
  check_slab(s, "slab_roulette_q01", 30.0, true, 40000);
}

TEST(FluorescenceSlab, BothSwitchesInFullModeWithContinuations) {
  // Nothing scatters and the pigment does not absorb where it emits, so `full`
  // (continuations included, their λ'' mixture using the uniform densities)
  // must still give the analytic slab.
  SlabSetup s;
  s.mode = "full";
  s.render_extra = std::string(kUniformExcitation) + kQRoulette;
  check_slab(s, "slab_full_switches_refl", 30.0, true, 20000);
  s.light = "\"D65\"";
  check_slab(s, "slab_full_switches_d65_trans", 10.0, false, 12000);
}

TEST(FluorescenceSlab, RouletteWithZeroQuantumYieldGivesExactlyZero) {
  // The loader never keeps a Q = 0 pigment, so set Q = 0 on a loaded scene: the
  // roulette itself must then return exactly zero, in direct and full mode.
  for (const char* mode : {"direct", "full"}) {
    SlabSetup s;
    s.mode = mode;
    s.render_extra = std::string(kQRoulette) + kUniformExcitation;
    Scene scene = slab_scene(s, std::string("slab_roulette_q0_") + mode, 0.0);
    ASSERT_TRUE(scene.has_fluorescence()) << mode;
    const auto lit = measure(scene, Ray{{0, 0, 1}, {0, 0, -1}}, 200, 1);
    EXPECT_GT(lit[1].sum, 0.0) << mode;  // the same scene fluoresces at Q = 0.5
    scene.fluorescence[0][0].quantum_yield = 0.f;
    const auto e = measure(scene, Ray{{0, 0, 1}, {0, 0, -1}}, 2000, 1);
    for (int k = 0; k < 4; ++k) EXPECT_EQ(e[k].sum, 0.0) << mode;
  }
}

TEST(FluorescenceSlab, ReferenceEstimatorIgnoresBothSwitches) {
  // The thesis's estimator already draws λ_e uniformly and uses Q as a roulette:
  // the switches leave it sample for sample unchanged, and the renderer says so.
  SlabSetup s;
  s.mode = "reference";
  const Scene plain = slab_scene(s, "slab_reference_plain", 30.0);
  s.render_extra = std::string(kUniformExcitation) + kQRoulette;
  const Scene switched = slab_scene(s, "slab_reference_switched", 30.0);
  EXPECT_NE(switched.settings.fluorescence_reason.find("do not apply"), std::string::npos)
      << switched.settings.fluorescence_reason;
  const auto a = measure(plain, Ray{{0, 0, 1}, {0, 0, -1}}, 2000, 8);
  const auto b = measure(switched, Ray{{0, 0, 1}, {0, 0, -1}}, 2000, 8);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(a[k].sum, b[k].sum);
}

TEST(FluorescenceSlab, ReferenceEstimatorBiasIsMeasured) {
  // The thesis's estimator (docs/physics.md §5) is kept to be measured, not trusted:
  // record its ratio to the exact slab radiance (printed and in the test XML).
  // It triggers emission by absorption at the emitted wavelength (here only the
  // solvent absorbs there, docs/physics.md §5 point 1), so its answer follows the
  // solvent, not the pigment.
  SlabSetup s;
  s.mode = "reference";
  const Scene scene = slab_scene(s, "slab_reference", 30.0);
  const SlabTruth truth{scene, s, 30.0};
  const auto e = measure(scene, Ray{{0, 0, 1}, {0, 0, -1}}, 20000, 8);
  for (int k = 0; k < 4; ++k) {
    const double ratio = e[k].mean() / truth.radiance(kEmissionLambdas[k], true);
    RecordProperty("reference_over_exact_" + std::to_string(int(kEmissionLambdas[k])), std::to_string(ratio));
    std::printf("reference estimator / exact at %.0f nm: %.4f ± %.4f\n", kEmissionLambdas[k], ratio,
                e[k].sigma() / truth.radiance(kEmissionLambdas[k], true));
    EXPECT_TRUE(std::isfinite(ratio));
  }
}

TEST(FluorescenceSlab, ReferenceEstimatorExcitesThroughGlass) {
  // The solution inside a glass box (the thesis's beaker scenes): the reference
  // estimator's excitation rays used to stop at the glass, so it rendered no
  // fluorescence at all there. They cross it like ours (Fresnel-weighted), and
  // stop only when the scene asks for "block".
  auto in_glass = [](const std::string& extra, const std::string& name) {
    SlabSetup s;
    s.mode = "reference";
    s.render_extra = extra;
    std::string json = slab_scene_json(s);
    const std::string interface = R"({"type": "interface"})";
    json.replace(json.find(interface), interface.size(), R"({"type": "dielectric", "ior": 1.5})");
    // It needs absorption at the emitted wavelengths to trigger events (docs/physics.md §5.1).
    const std::string solvent = R"("solvent": "none")";
    json.replace(json.find(solvent), solvent.size(), R"("solvent": {"absorption": 30, "rayleigh": false})");
    return load_scene(write_scene(name, json));
  };
  auto fluorescence_sum = [](const Scene& scene) {
    Estimate e;
    PathStats stats;
    const float pdf[4] = {1, 1, 1, 1};
    for (int i = 0; i < 20000; ++i) {
      Rng rng(test_seed(21), uint64_t(i));
      SampledWavelengths lambda = SampledWavelengths::from_values(kEmissionLambdas, pdf, 4);
      const PathRadiance L = trace_path(scene, Ray{{0, 0, 1}, {0, 0, -1}}, scene.camera_medium, lambda, rng, stats);
      e.add(L.fluorescence.average(4));
    }
    return e;
  };
  const Estimate through = fluorescence_sum(in_glass("", "slab_reference_glass"));
  EXPECT_GT(through.mean(), 4 * through.sigma()) << "no fluorescence inside glass";
  const Estimate blocked =
      fluorescence_sum(in_glass(R"(, "excitation_through_glass": "block")", "slab_reference_glass_block"));
  EXPECT_EQ(blocked.sum, 0.0);
}

// render.excitation_estimate = photons (integrator/excitation_photons.h).
namespace {

// ∫ over [lo, hi) of λ'·ε(λ')·E(λ')·∫_{d0}^{d1} Φ(d) dd dλ' for a collimated beam at
// normal incidence: the tally over the depths [d0, d1] below the slab's lit face.
// μ is the pigment's and the solvent's absorption; R the reflectance of each face
// (0 index-matched), so the fluence is the down- and up-going beams of
// Φ(d) = (1−R)(e^{-μd} + R e^{-μ(2D−d)}) / (1 − R² e^{-2μD}).
double beam_tally(const SlabTruth& truth, const Spectrum& E, double lo, double hi, double d0, double d1,
                  double R = 0.0) {
  const FluorescentPigment& fp = truth.scene.fluorescence[0][0];
  const double D = truth.setup.D, step = 0.02;
  double sum = 0;
  for (double lp = lo + 0.5 * step; lp < hi; lp += step) {
    const double mu = truth.mu_pigment(lp) + truth.solvent_absorption;
    if (!(mu > 0)) continue;
    const double down = (std::exp(-mu * d0) - std::exp(-mu * d1)) / mu;
    const double up = R * std::exp(-2 * mu * D) * (std::exp(mu * d1) - std::exp(mu * d0)) / mu;
    const double fluence = (1 - R) * (down + up) / (1 - R * R * std::exp(-2 * mu * D));
    sum += lp * fp.epsilon(float(lp)) * E(float(lp)) * fluence * step;
  }
  return sum;
}
// The beam comes down from +z: the slab's lit face is z = D.
constexpr double kSolvent = 30.0;  // 1/m: the emission is attenuated too, so the two faces differ

}  // namespace

TEST(ExcitationPhotons, SettingsAreReadAndChecked) {
  SlabSetup s;
  const Scene defaults = slab_scene(s, "slab_photons_default", 0.0);
  EXPECT_EQ(defaults.settings.excitation_estimate, ExcitationEstimate::rays);
  EXPECT_EQ(defaults.settings.excitation_photons_aimed, 0.5f);
  s.render_extra =
      R"(, "excitation_estimate": "photons", "excitation_photons": 5000, "excitation_grid_cells": 12, "excitation_photons_aimed": 0.8)";
  const Scene photons = slab_scene(s, "slab_photons_set", 0.0);
  EXPECT_EQ(photons.settings.excitation_estimate, ExcitationEstimate::photons);
  EXPECT_EQ(photons.settings.excitation_photons, 5000);
  EXPECT_EQ(photons.settings.excitation_grid_cells, 12);
  EXPECT_EQ(photons.settings.excitation_photons_aimed, 0.8f);
  for (const char* bad : {R"(, "excitation_estimate": "photon")", R"(, "excitation_photons": 0)",
                          R"(, "excitation_grid_cells": 65)", R"(, "excitation_photons_aimed": 1)",
                          R"(, "excitation_photons_aimed": -0.1)"}) {
    s.render_extra = bad;
    EXPECT_THROW(slab_scene(s, "slab_photons_bad", 0.0), InputError) << bad;
  }
  // A fluorescent medium no shape encloses (here the camera's) would get no grid.
  s.render_extra = R"(, "excitation_estimate": "photons")";
  std::string json = slab_scene_json(s);
  const std::string inside = ", \"inside\": \"solution\"";
  json.replace(json.find(inside), inside.size(), "");
  json.replace(json.find("\"lights\""), 0, "\"camera_medium\": \"solution\", ");
  try {
    load_scene(write_scene("slab_photons_unbounded", json));
    ADD_FAILURE() << "an unbounded fluorescent medium was accepted with photons";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("render.excitation_estimate"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no shape encloses"), std::string::npos) << e.what();
  }
}

// Photons under a collimated beam into a slab: every depth layer's tally, pooled over
// the cells away from the slab's edges, is the beam's (beam_tally) over the cell's
// height, within 4σ of the mean of those cells (their spread is the photons' noise).
// Index-matched, and as a liquid of index 1.33 whose faces reflect: the photons'
// power crosses a refraction uncompressed (radiance would be scaled by 1/η²).
namespace {

void check_slab_tally(bool refracting) {
  SlabSetup s;
  s.render_extra = R"(, "excitation_estimate": "photons")";
  std::string json = slab_scene_json(s);
  json.replace(json.find("\"solvent\": \"none\""), 17, "\"solvent\": {\"absorption\": 30, \"rayleigh\": false}");
  if (refracting) json.replace(json.find("{\"type\": \"interface\"}"), 21, "{\"type\": \"dielectric\", \"ior\": 1.33}");
  const Scene scene = load_scene(write_scene(refracting ? "slab_photons_tally_n133" : "slab_photons_tally", json));
  const double R = refracting ? std::pow(0.33 / 2.33, 2) : 0.0;
  PhotonTracing tracing;
  tracing.photons = 1 << 18;
  tracing.cells_per_axis = 16;
  const auto grids = trace_excitation_photons(scene, tracing);
  ASSERT_TRUE(grids);
  ASSERT_EQ(grids->size(), 1u);
  ASSERT_EQ((*grids)[0].size(), 1u);
  const ExcitationGrid& g = (*grids)[0][0];
  ASSERT_FALSE(g.empty());
  const SlabTruth truth{scene, s, kSolvent};
  const Spectrum& E = emission_spectrum(scene.lights[0]);
  const auto n = g.cells();
  ASSERT_GE(n[2], 8) << "a thin layer gets at least 8 cells across";
  const Vec3 lo = g.region().lo, size = g.region().diagonal();
  for (int iz = 0; iz < n[2]; ++iz) {
    const double c0 = lo.z + size.z * iz / n[2], c1 = lo.z + size.z * (iz + 1) / n[2];
    // The grid's region reaches past the slab: a cell astride its face averages over
    // the part inside the liquid only.
    const double in0 = std::max(0.0, c0), in1 = std::min(s.D, c1);
    const double exact =
        in1 > in0 ? beam_tally(truth, E, s.eps_lo - 1, s.eps_hi + 1, s.D - in1, s.D - in0, R) / (in1 - in0) : 0.0;
    Estimate pooled;
    for (int iy = 1; iy + 1 < n[1]; ++iy)
      for (int ix = 1; ix + 1 < n[0]; ++ix) {
        const float* v = g.at(lo + Vec3{(ix + 0.5f) * size.x / n[0], (iy + 0.5f) * size.y / n[1], float(0.5 * (c0 + c1) - lo.z)}).values;
        ASSERT_NE(v, nullptr);
        double sum = 0;
        for (int b = 0; b < ExcitationGrid::kBins; ++b) sum += v[b];
        pooled.add(sum);
      }
    if (exact == 0.0) {
      EXPECT_EQ(pooled.mean(), 0.0) << "layer " << iz << " lies outside the slab";
      continue;
    }
    EXPECT_NEAR(pooled.mean(), exact, 4 * pooled.sigma())
        << (refracting ? "n = 1.33, " : "") << "layer " << iz << ": rel.err " << pooled.mean() / exact - 1
        << " (σ/mean " << pooled.sigma() / exact << ")";
  }
}

// Events reading `g` (the slab's only grid) give the analytic slab's radiance
// seen from either face, within 4σ of 20 000 paths (plus `relative_slack`).
void expect_events_give_the_slab(const Scene& scene, const ExcitationGrid& g, const SlabTruth& truth, uint64_t seed,
                                 double relative_slack) {
  scene.excitation_grids =
      std::make_shared<const std::vector<std::vector<ExcitationGrid>>>(1, std::vector<ExcitationGrid>{g});
  for (const bool reflection_side : {true, false}) {
    const Ray ray = reflection_side ? Ray{{0, 0, 1}, {0, 0, -1}} : Ray{{0, 0, -1}, {0, 0, 1}};
    const auto e = measure(scene, ray, 20000, seed);
    for (int k = 0; k < 4; ++k) {
      const double exact = truth.radiance(kEmissionLambdas[k], reflection_side);
      EXPECT_NEAR(e[k].mean(), exact, 4 * e[k].sigma() + relative_slack * exact)
          << (reflection_side ? "lit face" : "far face") << ", λ=" << kEmissionLambdas[k] << " rel.err "
          << (e[k].mean() / exact - 1);
    }
  }
}

}  // namespace

TEST(ExcitationPhotons, SlabTallyIsTheCollimatedBeamsFluence) { check_slab_tally(false); }
TEST(ExcitationPhotons, SlabTallyInARefractingLiquidCountsBothFacesReflections) { check_slab_tally(true); }

// The event side alone: a grid holding the exact tally (256 layers, so the fluence's
// fall over a layer is negligible) gives the analytic slab's radiance.
TEST(ExcitationPhotons, EventsReadingTheExactTallyGiveTheSlabsRadiance) {
  SlabSetup s;
  s.render_extra = R"(, "excitation_estimate": "photons")";
  const Scene scene = slab_scene(s, "slab_photons_event", kSolvent);
  const SlabTruth truth{scene, s, kSolvent};
  const Spectrum& E = emission_spectrum(scene.lights[0]);
  constexpr int kLayers = 256;
  ExcitationGrid g(Bounds3{{-10, -10, 0}, {10, 10, float(s.D)}}, {1, 1, kLayers});
  for (int iz = 0; iz < kLayers; ++iz) {
    const double z0 = s.D * iz / kLayers, z1 = s.D * (iz + 1) / kLayers;
    for (int b = 0; b < ExcitationGrid::kBins; ++b) {
      const double half = 0.5 * (ExcitationGrid::bin_center(1) - ExcitationGrid::bin_center(0));
      const double c = ExcitationGrid::bin_center(b);
      const double value = beam_tally(truth, E, c - half, c + half, s.D - z1, s.D - z0) / (z1 - z0);
      // A vertical segment through the layer leaves value_per_length × its height.
      g.deposit({0, 0, float(z0)}, {0, 0, float(z1)}, b, float(value / (z1 - z0)));
    }
  }
  expect_events_give_the_slab(scene, g, truth, 29, 1e-4);
}

// A grid of 4 layers over a slab whose beam falls e-fold twice per layer and whose
// emission is seen from the first layer under either face: each layer's average
// alone reads the fluence as flat across the layer, while the camera's events
// crowd toward the face, so the radiance is off (−9 % on the lit face, +11 % on the
// other, 10σ); the layers' exponential profiles, from the tally's and the medium's
// moments, give the analytic slab within the events' noise (1 %).
TEST(ExcitationPhotons, EventsReadingACoarseGridGiveTheSlabsRadiance) {
  SlabSetup s;
  s.concentration = 100;  // µM: μ = 460 /m at the beam's wavelengths
  s.render_extra = R"(, "excitation_estimate": "photons")";
  constexpr double kMurkySolvent = 300;  // 1/m: the emission seen from either face comes from its first layer
  const Scene scene = slab_scene(s, "slab_photons_coarse", kMurkySolvent);
  const SlabTruth truth{scene, s, kMurkySolvent};
  const Spectrum& E = emission_spectrum(scene.lights[0]);
  constexpr int kLayers = 4, kSteps = 64;
  constexpr float kArea = 400.f;  // the grid's cross-section: one line of medium stands for all of it
  ExcitationGrid g(Bounds3{{-10, -10, 0}, {10, 10, float(s.D)}}, {1, 1, kLayers});
  for (int i = 0; i < kLayers * kSteps; ++i) {
    const double z0 = s.D * i / (kLayers * kSteps), z1 = s.D * (i + 1) / (kLayers * kSteps);
    for (int b = 0; b < ExcitationGrid::kBins; ++b) {
      const double half = 0.5 * (ExcitationGrid::bin_center(1) - ExcitationGrid::bin_center(0));
      const double c = ExcitationGrid::bin_center(b);
      const double tally = beam_tally(truth, E, c - half, c + half, s.D - z1, s.D - z0);
      g.deposit({0, 0, float(z0)}, {0, 0, float(z1)}, b, float(kArea * tally / (z1 - z0)));
    }
  }
  g.normalize(1.0, [&](ExcitationGrid& m) { m.add_medium_volume({0, 0, 0}, {0, 0, float(s.D)}, kArea); });
  expect_events_give_the_slab(scene, g, truth, 31, 0.0);
}

// Ctrl-C during the photon pre-pass: no grids are kept, so the render stops before
// its first pass (nothing written) and a later render traces them afresh.
TEST(ExcitationPhotons, AStopDuringThePrePassLeavesNoGrids) {
  SlabSetup s;
  s.render_extra = R"(, "excitation_estimate": "photons")";
  const Scene scene = slab_scene(s, "slab_photons_stop", 0.0);
  const std::atomic<bool> stop{true};
  EXPECT_FALSE(trace_excitation_photons(scene, PhotonTracing{}, &stop));
  prepare_excitation_grids(scene, 0, &stop);
  EXPECT_FALSE(scene.excitation_grids);
  prepare_excitation_grids(scene, 0);
  ASSERT_TRUE(scene.excitation_grids);
  EXPECT_NE(scene.excitation_grid(0, 0), nullptr);
}

// The photons' streams come from the render's seed: one seed gives one grid (parts
// of a render agree), another seed an independent one.
TEST(ExcitationPhotons, TheGridFollowsTheRendersSeed) {
  SlabSetup s;
  s.render_extra = R"(, "excitation_estimate": "photons", "excitation_photons": 20000, "excitation_grid_cells": 8)";
  const auto centre_cell = [&](uint64_t seed) {
    const Scene scene = slab_scene(s, "slab_photons_seed", 0.0);
    prepare_excitation_grids(scene, seed);
    const ExcitationGrid* g = scene.excitation_grid(0, 0);
    EXPECT_NE(g, nullptr);
    const float* v = g ? g->at(g->region().center()).values : nullptr;
    EXPECT_NE(v, nullptr);
    return v ? std::vector<float>(v, v + ExcitationGrid::kBins) : std::vector<float>{};
  };
  const std::vector<float> a = centre_cell(1), b = centre_cell(1), c = centre_cell(2);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

// The grid's reported noise (from its independent chunks) is the noise it has: two
// grids traced with different streams differ, cell by cell, by √2 times their
// reported standard errors (over the inner cells, whose medium volume is exact:
// the outer ones' is measured with the stream's own jitter), and four times the
// photons halve the grid's relative error.
TEST(ExcitationPhotons, TheGridsReportedErrorIsItsNoise) {
  SlabSetup s;
  s.render_extra = R"(, "excitation_estimate": "photons")";
  const Scene scene = slab_scene(s, "slab_photons_error", 0.0);
  const auto trace = [&](uint64_t seed, int64_t photons) {
    PhotonTracing tracing;
    tracing.photons = photons;
    tracing.cells_per_axis = 16;
    tracing.seed = seed;
    auto grids = trace_excitation_photons(scene, tracing);
    EXPECT_TRUE(grids);
    return grids ? (*grids)[0][0] : ExcitationGrid{};
  };
  const ExcitationGrid a = trace(1, 1 << 16), b = trace(2, 1 << 16), fine = trace(3, 1 << 18);
  ASSERT_FALSE(a.empty());
  ASSERT_GT(a.relative_error(), 0.f);
  const auto n = a.cells();
  double difference = 0, reported = 0;
  int inner = 0;
  for (int iz = 1; iz + 1 < n[2]; ++iz)
    for (int iy = 1; iy + 1 < n[1]; ++iy)
      for (int ix = 1; ix + 1 < n[0]; ++ix) {
        const size_t c = size_t((iz * n[1] + iy) * n[0] + ix);
        const double d = a.cell_total(c) - b.cell_total(c);
        difference += d * d;
        reported += a.cell_error(c) * a.cell_error(c) + b.cell_error(c) * b.cell_error(c);
        ++inner;
      }
  ASSERT_GT(inner, 100);
  // A photon crosses a whole column of the thin slab's cells, so the columns are the
  // independent units: Σ d² has a relative standard deviation of about √(2/columns),
  // its square root half that; 4 of them bound the ratio.
  const int columns = (n[0] - 2) * (n[1] - 2);
  const double ratio = std::sqrt(difference / reported);
  EXPECT_NEAR(ratio, 1.0, 0.5 * 4 * std::sqrt(2.0 / columns)) << columns << " inner columns";
  EXPECT_NEAR(fine.relative_error() / a.relative_error(), 0.5, 0.05);
}
