#include <gtest/gtest.h>

#include <vector>

#include "chi_square.h"
#include "core/rng.h"
#include "media/medium_phase.h"
#include "media/phase.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

namespace {

// Probability of each of `bins` equal bins of cos theta in [-1, 1] under the
// phase function's value (Simpson's rule on 2 pi p(mu)): independent of the sampler.
std::vector<double> expected_bin_probabilities(const std::function<double(float)>& p, int bins) {
  std::vector<double> prob(bins);
  const int steps = 200;  // per bin, even
  for (int b = 0; b < bins; ++b) {
    const double lo = -1.0 + 2.0 * b / bins, h = 2.0 / bins / steps;
    double s = 0;
    for (int i = 0; i <= steps; ++i) {
      const double w = (i == 0 || i == steps) ? 1 : (i % 2 ? 4 : 2);
      s += w * 2.0 * 3.14159265358979 * p(float(lo + i * h));
    }
    prob[b] = s * h / 3.0;
  }
  return prob;
}

const Vec3 kWo = normalize(Vec3{0.3f, -0.5f, 0.8f});

void expect_sampling_matches(const PhaseFunction& phase, uint64_t seed) {
  constexpr int kBins = 60, kSamples = 400000;
  std::vector<double> observed(kBins, 0.0);
  Rng rng(test_seed(seed), 0);
  for (int i = 0; i < kSamples; ++i) {
    const PhaseSample s = phase_sample(phase, kWo, {rng.uniform(), rng.uniform()});
    ASSERT_NEAR(length(s.wi), 1.f, 1e-4f);
    const float c = dot(kWo, s.wi);
    ASSERT_NEAR(s.pdf, phase_eval(phase, kWo, s.wi), 1e-3f * s.pdf + 1e-6f);
    ASSERT_EQ(s.p, s.pdf);
    observed[std::min(kBins - 1, int((c + 1.f) * 0.5f * kBins))] += 1;
  }
  std::vector<double> expected = expected_bin_probabilities([&](float c) { return phase_eval(phase, c); }, kBins);
  double total = 0;
  for (double& e : expected) total += e, e *= kSamples;
  EXPECT_NEAR(total, 1.0, 1e-4);  // normalised
  int dof;
  const double chi2 = test::chi_square(observed, expected, &dof);
  EXPECT_LT(chi2, test::chi_square_quantile(dof, 3.72)) << "dof " << dof;
}

}  // namespace

TEST(Phase, RayleighSamplingMatchesItsPdf) { expect_sampling_matches(Rayleigh{}, 1); }
TEST(Phase, IsotropicSamplingMatchesItsPdf) { expect_sampling_matches(Isotropic{}, 2); }
TEST(Phase, HenyeyGreensteinSamplingMatchesItsPdf) {
  uint64_t seed = 3;
  for (float g : {-0.9f, -0.3f, 0.f, 5e-4f, 0.2f, 0.7f, 0.95f}) {
    SCOPED_TRACE(g);
    expect_sampling_matches(HenyeyGreenstein{g}, seed++);
  }
}

TEST(Phase, RayleighInverseCdfHitsTheEndsAndTheMiddle) {
  EXPECT_NEAR(sample_rayleigh_cos_theta(0.f), -1.f, 1e-6f);
  EXPECT_NEAR(sample_rayleigh_cos_theta(0.5f), 0.f, 1e-6f);
  EXPECT_NEAR(sample_rayleigh_cos_theta(0x1.fffffep-1f), 1.f, 1e-5f);
  // F(mu) = (mu^3 + 3 mu + 4) / 8 inverts exactly.
  for (float u = 0.01f; u < 1.f; u += 0.01f) {
    const float mu = sample_rayleigh_cos_theta(u);
    EXPECT_NEAR((mu * mu * mu + 3.f * mu + 4.f) / 8.f, u, 2e-6f);
  }
}

TEST(Phase, HenyeyGreensteinForwardMeansAwayFromWo) {
  // pbrt convention: with g > 0 light keeps going, so wi is near -wo.
  Rng rng(test_seed(9), 0);
  double mean = 0;
  for (int i = 0; i < 100000; ++i) mean += dot(kWo, phase_sample(HenyeyGreenstein{0.6f}, kWo, {rng.uniform(), rng.uniform()}).wi);
  EXPECT_NEAR(mean / 100000, -0.6, 0.01);  // mean cosine is g, measured from the propagation direction
}

TEST(MediumPhase, MixtureIsPerLaneAndSampledFromTheHeroWeights) {
  MediumPhase phase{HenyeyGreenstein{0.8f}, {}};
  phase.particle_fraction[0] = 0.5f;
  phase.particle_fraction[1] = 0.f;   // this lane sees molecules only
  phase.particle_fraction[2] = 1.f;   // this one particles only
  constexpr int kBins = 60, kSamples = 400000;
  std::vector<double> observed(kBins, 0.0);
  Rng rng(test_seed(10), 0);
  for (int i = 0; i < kSamples; ++i) {
    const MediumPhaseSample s = phase_sample(phase, kWo, {rng.uniform(), rng.uniform()});
    const float c = dot(kWo, s.wi);
    ASSERT_NEAR(s.pdf, phase_pdf(phase, kWo, s.wi), 1e-6f);
    ASSERT_NEAR(s.p[1], rayleigh_phase(c), 1e-5f);
    ASSERT_NEAR(s.p[2], henyey_greenstein(c, 0.8f), 1e-4f * s.p[2]);
    ASSERT_NEAR(s.p[0], s.pdf, 1e-4f * s.pdf);  // the hero lane is sampled exactly
    observed[std::min(kBins - 1, int((c + 1.f) * 0.5f * kBins))] += 1;
  }
  std::vector<double> expected =
      expected_bin_probabilities([&](float c) { return 0.5 * rayleigh_phase(c) + 0.5 * henyey_greenstein(c, 0.8f); }, kBins);
  for (double& e : expected) e *= kSamples;
  int dof;
  const double chi2 = test::chi_square(observed, expected, &dof);
  EXPECT_LT(chi2, test::chi_square_quantile(dof, 3.72)) << "dof " << dof;
}
