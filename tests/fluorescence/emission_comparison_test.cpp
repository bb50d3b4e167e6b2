// docs/physics.md §4: the mirror-image emission of chlorophyll a compared with the
// measured emission (same solvent, diethyl ether) and the ocean-optics Gaussian.
// The figures are printed and recorded (docs/fluorescence.md quotes them); the
// assertions only pin what must hold for any sane emission spectrum.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "fluorescence/emission_spectrum.h"
#include "spectra/library.h"

using namespace chlorovdb;

namespace {

struct Shape {
  float peak_nm, mean_nm, fwhm_nm;
};

Shape shape_of(const Spectrum& f) {
  float peak = 0, peak_l = 0;
  double m0 = 0, m1 = 0;
  for (float l = 600; l <= 830; l += 0.05f) {
    const float v = f(l);
    if (v > peak) peak = v, peak_l = l;
    m0 += v, m1 += v * l;
  }
  float lo = peak_l, hi = peak_l;
  while (lo > 600 && f(lo) > peak / 2) lo -= 0.05f;
  while (hi < 830 && f(hi) > peak / 2) hi += 0.05f;
  return {peak_l, float(m1 / m0), hi - lo};
}

double l1_distance(const Spectrum& a, const Spectrum& b) {
  double d = 0;
  for (float l = kLambdaMinUV; l < kLambdaMax; l += 0.05f) d += std::fabs(a(l) - b(l)) * 0.05;
  return d;  // both integrate to 1, so this is in [0, 2]
}

}  // namespace

TEST(EmissionComparison, MirrorImageGaussianAndMeasuredChlorophyllA) {
  const Spectrum epsilon = named_spectrum("chlorophyll_a");
  const Spectrum measured = normalise_emission(named_spectrum("chlorophyll_a_emission"));
  const Spectrum mirror673 = mirror_image_emission(epsilon);  // the reference's axis
  MirrorImageBand fitted;
  fitted.mirror_nm = 663.f;  // midway between ε's red peak (660 nm) and the measured emission peak (666 nm)
  const Spectrum mirror663 = mirror_image_emission(epsilon, fitted);
  const Spectrum gaussian = gaussian_emission();

  const struct {
    const char* name;
    const Spectrum& f;
  } all[] = {{"measured (ether)", measured}, {"mirror @673", mirror673}, {"mirror @663", mirror663},
             {"gaussian 685/10.6", gaussian}};
  for (const auto& [name, f] : all) {
    const Shape s = shape_of(f);
    std::printf("%-18s peak %6.1f nm  mean %6.1f nm  FWHM %5.1f nm  L1 to measured %.3f\n", name, s.peak_nm,
                s.mean_nm, s.fwhm_nm, l1_distance(f, measured));
    RecordProperty(std::string(name) + " peak_nm", std::to_string(s.peak_nm));
    EXPECT_NEAR(f.integral(kLambdaMinUV, kLambdaMax), 1.f, 2e-3f) << name;
    EXPECT_GT(s.peak_nm, 640.f) << name;
    EXPECT_LT(s.peak_nm, 700.f) << name;
  }
  // The mirror about 673 nm lands ~20 nm redder than the measured ether emission:
  // the rule needs the 0-0 transition of the solvent the table was measured in.
  EXPECT_GT(shape_of(mirror673).peak_nm - shape_of(measured).peak_nm, 10.f);
  EXPECT_LT(l1_distance(mirror663, measured), l1_distance(mirror673, measured));
}
