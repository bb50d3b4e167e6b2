#include <gtest/gtest.h>

#include "core/error.h"
#include "media/pigment.h"
#include "media/solvent.h"

using namespace chlorovdb;

TEST(Solvent, WaterRayleighScatteringMatchesPhysicsNote) {
  // docs/physics.md §2: about 2.6e-3 /m; 1.6e-4 /m would mean the 16 pi / 3 was dropped.
  const float s = water_rayleigh_sigma_s(500.f, 1.337f, 293.f);
  EXPECT_NEAR(s, 2.60e-3f, 0.02e-3f);
  // lambda^-4 and linear in temperature.
  EXPECT_NEAR(water_rayleigh_sigma_s(250.f, 1.337f, 293.f) / s, 16.f, 1e-3f);
  EXPECT_NEAR(water_rayleigh_sigma_s(500.f, 1.337f, 586.f) / s, 2.f, 1e-5f);
  EXPECT_EQ(water_rayleigh_sigma_s(500.f, 1.f, 293.f), 0.f);  // no index contrast, no scattering
}

TEST(Pigment, AbsorptionFromDecadicMolarExtinction) {
  // docs/physics.md §1: eps = 85 265 L/mol/cm at 5 uM gives about 98 /m.
  EXPECT_NEAR(kAbsorptionPerMolarExtinction * 85265.f * 5e-6f, 98.16f, 0.01f);
}

TEST(Pigment, ValidationNamesTheProblem) {
  Pigment p{"chl", Spectrum::constant(1000.f), Spectrum::constant(0.f), 0.f};
  EXPECT_NO_THROW(validate(p, "s.json", "media.m.pigments[0]"));
  p.quantum_yield = 1.5f;
  EXPECT_THROW(validate(p, "s.json", "k"), InputError);
  p.quantum_yield = 0.3f;  // fluorescent but no emission spectrum
  EXPECT_THROW(validate(p, "s.json", "k"), InputError);
  p.emission = Spectrum::tabulated({600.f, 700.f}, {0.02f, 0.02f});  // integrates to 2
  try {
    validate(p, "s.json", "media.m.pigments[0]");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("media.m.pigments[0].emission"), std::string::npos) << e.what();
  }
  p.emission = Spectrum::tabulated({600.f, 700.f}, {0.01f, 0.01f});
  EXPECT_NO_THROW(validate(p, "s.json", "k"));
  p.epsilon = Spectrum::tabulated({400.f, 500.f}, {10.f, -1.f});
  EXPECT_THROW(validate(p, "s.json", "k"), InputError);
}

TEST(Pigment, ConcentrationUnits) {
  EXPECT_EQ(molar_per_unit("uM", "f", "k"), 1e-6f);
  EXPECT_EQ(molar_per_unit("µM", "f", "k"), 1e-6f);
  EXPECT_EQ(molar_per_unit("mM", "f", "k"), 1e-3f);
  EXPECT_EQ(molar_per_unit("M", "f", "k"), 1.f);
  EXPECT_THROW(molar_per_unit("ppm", "f", "k"), InputError);
}
