#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "fluorescence/emission_spectrum.h"
#include "fluorescence/excitation_sampler.h"
#include "fluorescence/redistribution.h"
#include "spectra/library.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

TEST(EmissionSpectrum, MirrorImageOfChlorophyllIsNormalisedAndPeaksNear686nm) {
  const Spectrum f = mirror_image_emission(named_spectrum("chlorophyll_a"));
  EXPECT_NEAR(f.integral(kLambdaMinUV, kLambdaMax), 1.f, 1e-4f);
  // ε peaks at ~660 nm (ether), so the mirror about 673 nm peaks at ~686 nm.
  float best = 0, best_l = 0;
  for (float l = 640; l < 760; l += 0.1f)
    if (f(l) > best) best = f(l), best_l = l;
  EXPECT_NEAR(best_l, 2 * 673.f - 660.f, 3.f);
  // Nothing from the Soret band: no emission below the mirrored band edge.
  EXPECT_EQ(f(640.f), 0.f);
}

TEST(EmissionSpectrum, GaussianIsNormalised) {
  const Spectrum g = gaussian_emission();
  EXPECT_NEAR(g.integral(kLambdaMinUV, kLambdaMax), 1.f, 1e-4f);
  EXPECT_GT(g(685.f), g(680.f));
}

namespace {

// Draws n samples of λ' and checks each lies in the sampler's support with the pdf it
// reports, and that the estimate of ∫ S ε λ' is unbiased within 4σ.
void expect_unbiased_excitation(const ExcitationSampler& sampler, const Spectrum& light, const Spectrum& eps, int n,
                                uint64_t seed) {
  Rng rng(test_seed(seed), 0);
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    float pdf;
    const float l = sampler.sample(rng.uniform(), &pdf);
    ASSERT_GT(pdf, 0.f);
    ASSERT_GE(l, sampler.support_min());
    ASSERT_LT(l, sampler.support_max());
    ASSERT_FLOAT_EQ(pdf, sampler.pdf(l));
    const double g = double(light(l)) * eps(l) * l / pdf;
    sum += g;
    sum2 += g * g;
  }
  const double mean = sum / n, sigma = std::sqrt((sum2 / n - mean * mean) / n);
  EXPECT_NEAR(mean, sampler.total(), 4 * sigma + 1e-3 * sampler.total());
}

}  // namespace

TEST(ExcitationSampler, EstimatesItsOwnIntegralAndPdfMatchesSamples) {
  const Spectrum light = named_spectrum("F2");
  const Spectrum eps = named_spectrum("chlorophyll_a");
  const ExcitationSampler sampler(light, eps);
  ASSERT_TRUE(sampler.can_excite());
  // ∫ pdf = 1 on the tabulation.
  double integral = 0;
  for (float l = kLambdaMinUV; l < kLambdaMax; l += 0.05f) integral += sampler.pdf(l + 0.025f) * 0.05;
  EXPECT_NEAR(integral, 1.0, 1e-3);
  // Importance sampling estimate of ∫ S ε λ: unbiased within 4σ.
  expect_unbiased_excitation(sampler, light, eps, 200000, 7);
}

TEST(ExcitationSampler, UniformModePdfIntegratesToOneOverTheImportanceSupport) {
  // render.excitation_sampling = uniform: λ' uniform over the bins where S·ε·λ'
  // is positive, so it covers everything the importance sampler covers.
  const Spectrum light = named_spectrum("F2");
  const Spectrum eps = named_spectrum("chlorophyll_a");
  const ExcitationSampler importance(light, eps);
  const ExcitationSampler uniform(light, eps, ExcitationSampling::uniform);
  ASSERT_TRUE(uniform.can_excite());
  EXPECT_EQ(uniform.mode(), ExcitationSampling::uniform);
  EXPECT_EQ(uniform.total(), importance.total());
  EXPECT_LT(uniform.support_min(), uniform.support_max());
  const float p = uniform.pdf(0.5f * (uniform.support_min() + uniform.support_max()));
  EXPECT_NEAR(double(p) * (double(uniform.support_max()) - uniform.support_min()), 1.0, 1e-6);
  double integral = 0;
  for (float l = kLambdaMinUV; l < kLambdaMax; l += 0.05f) {
    const float lm = l + 0.025f;
    integral += uniform.pdf(lm) * 0.05;
    if (importance.pdf(lm) > 0.f) EXPECT_EQ(uniform.pdf(lm), p) << lm;  // same support
    if (uniform.pdf(lm) > 0.f) EXPECT_EQ(uniform.pdf(lm), p) << lm;      // flat
  }
  EXPECT_NEAR(integral, 1.0, 1e-3);
  EXPECT_EQ(uniform.pdf(uniform.support_min() - 0.01f), 0.f);
  EXPECT_EQ(uniform.pdf(uniform.support_max()), 0.f);
  // Samples stay inside, carry the pdf, and estimate ∫ S ε λ without bias.
  expect_unbiased_excitation(uniform, light, eps, 400000, 11);
  for (float u : {0.f, 0.99999994f}) {
    float pdf;
    const float l = uniform.sample(u, &pdf);
    EXPECT_EQ(pdf, uniform.pdf(l)) << u;
  }
}

TEST(ExcitationSampler, LightDarkWhereThePigmentAbsorbsCannotExcite) {
  // A narrow light at 750 nm: chlorophyll a's table ends at 700 nm (zero beyond).
  const ExcitationSampler sampler(Spectrum::gaussian(760.f, 2.f), named_spectrum("chlorophyll_a"));
  EXPECT_FALSE(sampler.can_excite());
}

TEST(Redistribution, StokesWeightKeepsPhotonCountPerAbsorbedPhoton) {
  const Spectrum f = gaussian_emission();
  const RedistributionWeight w(Redistribution::stokes, f);
  for (float excitation : {400.f, 660.f, 680.f, 690.f}) {
    double photons_out = 0;
    for (float l = kLambdaMinUV; l < kLambdaMax; l += 0.01f) photons_out += f(l) * w(excitation, l) * 0.01;
    EXPECT_NEAR(photons_out, 1.0, 5e-3) << "excitation " << excitation;
  }
  EXPECT_EQ(w(700.f, 690.f), 0.f);  // anti-Stokes excluded
  const RedistributionWeight kv(Redistribution::kasha_vavilov, f);
  EXPECT_EQ(kv(700.f, 690.f), 1.f);
}
