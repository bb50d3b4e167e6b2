#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/rng.h"
#include "spectra/color.h"
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

// A mercury line (Gaussian, σ = 0.4 nm, at 546 nm; 81 % of the power) on a weak flat background,
// as a lamp's visible spectrum: what the scene's camera-wavelength mixture is for.
double line_lamp(float lambda) {
  const double d = (lambda - 546.0) / 0.4;
  return 200.0 * std::exp(-0.5 * d * d) + 0.1;
}

WavelengthDistribution eye_and_lamp() {
  return WavelengthDistribution::mixture(
      {{[](float l) { return double(visible_wavelength_pdf(l)); }, 0.5}, {line_lamp, 0.5}});
}

TEST(WavelengthDistribution, MixtureIsADensityItsSamplesFollow) {
  const WavelengthDistribution d = eye_and_lamp();
  ASSERT_FALSE(d.is_visible());
  double sum = 0;  // piecewise constant: its bins' midpoints integrate it exactly
  for (float l = kLambdaMin + 0.5f * WavelengthDistribution::kBinWidth; l < kLambdaMax; l += WavelengthDistribution::kBinWidth)
    sum += d.pdf(l) * WavelengthDistribution::kBinWidth;
  EXPECT_NEAR(sum, 1.0, 1e-5);
  EXPECT_EQ(d.pdf(kLambdaMin - 1.f), 0.f);
  EXPECT_EQ(d.pdf(kLambdaMax + 1.f), 0.f);
  // Half the mass is the lamp's, and 81 % of the lamp's is its line.
  double line_mass = 0;
  for (float l = 544.25f; l < 548.f; l += 0.5f) line_mass += d.pdf(l) * 0.5;
  EXPECT_GT(line_mass, 0.35);

  // Chi-square over 2 nm bins, with the line's bins among them.
  const int bins = 235, n = 400000;
  const float width = (kLambdaMax - kLambdaMin) / bins;
  std::vector<int> hist(bins, 0);
  Rng rng(test_seed(29), 0);
  for (int k = 0; k < n; ++k) {
    const SampledWavelengths w = d.sample(rng.uniform(), 1);
    ASSERT_GE(w[0], kLambdaMin);
    ASSERT_LE(w[0], kLambdaMax);
    ASSERT_EQ(w.pdf(0), d.pdf(w[0])) << w[0];
    ++hist[std::min(bins - 1, int((w[0] - kLambdaMin) / width))];
  }
  double chi2 = 0;
  int dof = -1;
  for (int b = 0; b < bins; ++b) {
    double p = 0;
    for (int j = 0; j < 4; ++j) p += d.pdf(kLambdaMin + width * (b + (j + 0.5f) / 4)) * width / 4;
    const double expected = n * p;
    if (expected < 5) continue;
    chi2 += (hist[b] - expected) * (hist[b] - expected) / expected;
    ++dof;
  }
  ASSERT_GT(dof, 200);
  // P(chi2 > dof + 4 sqrt(2 dof)) < 1e-3 for dof in the hundreds.
  EXPECT_LT(chi2, dof + 4 * std::sqrt(2.0 * dof));
}

// sample() inverts the mixture's CDF: checked against a CDF the test sums from pdf()
// at every bin edge in u, the floats beside it, and 10 000 points between.
TEST(WavelengthDistribution, SampleInvertsTheMixturesCdf) {
  const WavelengthDistribution d = eye_and_lamp();
  const float w = WavelengthDistribution::kBinWidth;
  const int bins = int(std::lround((kLambdaMax - kLambdaMin) / w));
  std::vector<double> cdf{0.0};
  for (int b = 0; b < bins; ++b) cdf.push_back(cdf.back() + double(d.pdf(kLambdaMin + w * (b + 0.5f))) * w);
  const auto expected = [&](double u) {
    const int b = std::clamp(int(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin()) - 1, 0, bins - 1);
    return kLambdaMin + w * (b + float((u - cdf[b]) / (cdf[b + 1] - cdf[b])));
  };
  const auto check = [&](float u) {
    if (!(u >= 0.f && u < 1.f)) return;
    ASSERT_NEAR(d.sample(u, 1)[0], expected(u), 2e-3) << "u = " << u;
  };
  for (int b = 0; b < bins; ++b) {
    const float edge = float(cdf[b]);
    check(edge);
    check(std::nextafter(edge, 0.f));
    check(std::nextafter(edge, 1.f));
  }
  for (int k = 0; k < 10000; ++k) check(float(k) / 10000.f);
}

TEST(WavelengthDistribution, LanesAreStratifiedInTheMixturesCdf) {
  const WavelengthDistribution d = eye_and_lamp();
  const int count = 4;
  const SampledWavelengths w = d.sample(0.6f, count);
  ASSERT_EQ(w.count(), count);
  const float strata[count] = {0.6f, 0.85f, 0.1f, 0.35f};
  for (int i = 0; i < count; ++i) {
    const SampledWavelengths one = d.sample(strata[i], 1);
    EXPECT_NEAR(w[i], one[0], 1e-3f) << i;
    EXPECT_EQ(w.pdf(i), one.pdf(0)) << i;
  }
  for (int i = count; i < kMaxWavelengths; ++i) EXPECT_EQ(w.pdf(i), 0.f);
}

// ∫ lamp(λ) ȳ(λ) dλ estimated from lanes drawn by each density: both agree with the
// integral within 4σ, and the mixture's standard error is a fraction of the eye's,
// which finds the line only by chance.
TEST(WavelengthDistribution, LineSpectrumIsEstimatedWithoutItsTail) {
  double exact = 0;
  for (double l = kLambdaMin; l < kLambdaMax; l += 0.01) exact += line_lamp(float(l + 0.005)) * cie_cmf(float(l + 0.005)).y * 0.01;
  const WavelengthDistribution mixture = eye_and_lamp(), eye = WavelengthDistribution::visible();
  double sigma[2];
  for (int k = 0; k < 2; ++k) {
    const WavelengthDistribution& d = k == 0 ? mixture : eye;
    Rng rng(test_seed(31), uint64_t(k));
    double sum = 0, sum2 = 0;
    const int n = 20000, count = 4;
    for (int i = 0; i < n; ++i) {
      const SampledWavelengths w = d.sample(rng.uniform(), count);
      double x = 0;
      for (int j = 0; j < count; ++j) x += line_lamp(w[j]) * cie_cmf(w[j]).y / w.pdf(j) / count;
      sum += x;
      sum2 += x * x;
    }
    const double mean = sum / n;
    sigma[k] = std::sqrt((sum2 / n - mean * mean) / n);
    EXPECT_NEAR(mean, exact, 4 * sigma[k]) << (k == 0 ? "mixture" : "eye");
  }
  EXPECT_LT(sigma[0], 0.2 * sigma[1]) << "mixture " << sigma[0] << ", eye " << sigma[1];
}

TEST(WavelengthDistribution, MixtureRefusesBadComponents) {
  const auto flat = [](float) { return 1.0; };
  EXPECT_THROW(WavelengthDistribution::mixture({{flat, -0.5}}), std::invalid_argument);
  EXPECT_THROW(WavelengthDistribution::mixture({{flat, std::nan("")}}), std::invalid_argument);
  EXPECT_THROW(WavelengthDistribution::mixture({{[](float) { return -1.0; }, 1.0}}), std::invalid_argument);
  EXPECT_THROW(WavelengthDistribution::mixture({{[](float) { return std::nan(""); }, 1.0}}), std::invalid_argument);
  // Dark over the camera range: left out; nothing left is an error.
  EXPECT_THROW(WavelengthDistribution::mixture({{[](float) { return 0.0; }, 1.0}}), std::invalid_argument);
  const WavelengthDistribution only_flat = WavelengthDistribution::mixture({{flat, 0.7}, {[](float) { return 0.0; }, 0.3}});
  EXPECT_NEAR(only_flat.pdf(500.f), 1.0 / (kLambdaMax - kLambdaMin), 1e-6);
}
