#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/rng.h"
#include "spectra/sampled.h"
#include "spectra/wavelength_sampling.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

TEST(WavelengthSampling, VisiblePdfIntegratesToOne) {
  double sum = 0;
  const int n = 470000;
  const double h = (kLambdaMax - kLambdaMin) / n;
  for (int i = 0; i < n; ++i) sum += visible_wavelength_pdf(float(kLambdaMin + (i + 0.5) * h)) * h;
  EXPECT_NEAR(sum, 1.0, 1e-5);
  EXPECT_EQ(visible_wavelength_pdf(359.f), 0.f);
  EXPECT_EQ(visible_wavelength_pdf(831.f), 0.f);
}

TEST(WavelengthSampling, SamplesMatchThePdfChiSquare) {
  const int bins = 47, n = 200000;
  std::vector<int> hist(bins, 0);
  Rng rng(test_seed(17), 0);
  const float width = (kLambdaMax - kLambdaMin) / bins;
  for (int k = 0; k < n; ++k) {
    const SampledWavelengths w = SampledWavelengths::sample_visible(rng.uniform(), 1);
    ASSERT_GE(w[0], kLambdaMin);
    ASSERT_LE(w[0], kLambdaMax);
    // sample_visible computes its pdf from tanh(a(λ−c)) in float, not from the rounded λ:
    // a few 1e-7 apart, far below anything an estimator could see.
    ASSERT_NEAR(w.pdf(0), visible_wavelength_pdf(w[0]), 1e-5f * visible_wavelength_pdf(w[0]));
    ++hist[std::min(bins - 1, int((w[0] - kLambdaMin) / width))];
  }
  double chi2 = 0;
  for (int b = 0; b < bins; ++b) {
    double p = 0;  // bin probability by midpoint quadrature
    const int m = 1000;
    for (int j = 0; j < m; ++j) p += visible_wavelength_pdf(kLambdaMin + width * (b + (j + 0.5f) / m)) * width / m;
    const double expected = n * p;
    chi2 += (hist[b] - expected) * (hist[b] - expected) / expected;
  }
  // 46 degrees of freedom: P(chi2 > 81.4) = 0.001.
  EXPECT_LT(chi2, 81.4);
}

TEST(WavelengthSampling, LanesAreStratified) {
  const int count = 4;
  const float u = 0.6f;
  const SampledWavelengths w = SampledWavelengths::sample_visible(u, count);
  ASSERT_EQ(w.count(), count);
  const float strata[count] = {0.6f, 0.85f, 0.1f, 0.35f};
  for (int i = 0; i < count; ++i) EXPECT_NEAR(w[i], sample_visible_wavelength(strata[i]), 1e-3f);
  for (int i = count; i < kMaxWavelengths; ++i) EXPECT_EQ(w.pdf(i), 0.f);
}

TEST(WavelengthSampling, InverseCdfCoversTheRange) {
  EXPECT_NEAR(sample_visible_wavelength(0.f), kLambdaMin, 1e-3f);
  EXPECT_NEAR(sample_visible_wavelength(0x1.fffffep-1f), kLambdaMax, 1e-2f);
}

TEST(WavelengthSampling, UniformSampling) {
  const SampledWavelengths w = SampledWavelengths::sample_uniform(0.25f, 2, 400, 500);
  EXPECT_FLOAT_EQ(w[0], 425.f);
  EXPECT_FLOAT_EQ(w[1], 475.f);
  EXPECT_FLOAT_EQ(w.pdf(1), 0.01f);
  EXPECT_THROW(SampledWavelengths::sample_uniform(0.f, 1, 500, 400), std::invalid_argument);
}

TEST(WavelengthSampling, CountMustBeInRange) {
  EXPECT_THROW(SampledWavelengths::sample_visible(0.5f, 0), std::invalid_argument);
  EXPECT_THROW(SampledWavelengths::sample_visible(0.5f, kMaxWavelengths + 1), std::invalid_argument);
  EXPECT_NO_THROW(SampledWavelengths::sample_visible(0.5f, kMaxWavelengths));
}
