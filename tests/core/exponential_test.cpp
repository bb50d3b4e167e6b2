#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/exponential.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

namespace {

std::vector<double> samples(int n, uint64_t seed) {
  Rng rng(test_seed(seed), 0);
  std::vector<double> x(n);
  for (double& v : x) v = sample_standard_exponential(rng);
  return x;
}

}  // namespace

TEST(ExponentialZiggurat, TablesDescribeEqualAreaLayers) {
  const ExponentialZiggurat& z = kExponentialZiggurat;
  // Outer edges x_i = w[i] * 2^24 decrease toward the peak; f[i] = e^{-x_i}.
  for (int i = 2; i < ExponentialZiggurat::kLayers; ++i) {
    const double x = double(z.w[i]) * 16777216.0, x_inner = double(z.w[i - 1]) * 16777216.0;
    EXPECT_LT(x_inner, x) << i;
    EXPECT_NEAR(z.f[i], std::exp(-x), 1e-6 * std::exp(-x)) << i;
    // Every layer above the base holds the same area: x_i * (f[i-1] - f[i]).
    EXPECT_NEAR(x * (double(z.f[i - 1]) - double(z.f[i])), 3.949659822581572e-3, 5e-5 * 3.949659822581572e-3) << i;  // f is float
  }
  EXPECT_NEAR(double(z.w[255]) * 16777216.0, ExponentialZiggurat::kTailStart, 1e-5);
}

TEST(ExponentialZiggurat, FollowsTheExponentialDistribution) {
  // Kolmogorov-Smirnov against 1 - e^{-x}, and the mean, variance and far tail
  // within 4 standard errors (fixed seed).
  const int n = 400000;
  std::vector<double> x = samples(n, 11);
  double sum = 0, sum2 = 0;
  int beyond = 0;  // past the base layer's start: exercises the tail branch
  for (double v : x) {
    ASSERT_GE(v, 0.0);
    ASSERT_TRUE(std::isfinite(v));
    sum += v;
    sum2 += v * v;
    beyond += v > ExponentialZiggurat::kTailStart;
  }
  const double mean = sum / n, var = sum2 / n - mean * mean;
  EXPECT_NEAR(mean, 1.0, 4.0 / std::sqrt(double(n)));  // sd of x is 1
  EXPECT_NEAR(var, 1.0, 4.0 * std::sqrt(8.0 / n));  // sd of the sample variance: sqrt((mu_4 - 1) / n), mu_4 = 9
  const double p_tail = std::exp(-ExponentialZiggurat::kTailStart);
  EXPECT_NEAR(double(beyond) / n, p_tail, 4.0 * std::sqrt(p_tail / n));
  EXPECT_GT(beyond, 0);
  std::sort(x.begin(), x.end());
  double d = 0;
  for (int i = 0; i < n; ++i) {
    const double F = 1.0 - std::exp(-x[i]);
    d = std::max({d, std::fabs(double(i) / n - F), std::fabs(double(i + 1) / n - F)});
  }
  EXPECT_LT(d * std::sqrt(double(n)), 1.95);  // alpha = 0.001
}
