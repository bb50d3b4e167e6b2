// The von Mises-Fisher lobe of core/sampling.h: its pdf is normalised and is the
// density of its samples, for the small and large concentrations the
// continuation lobes use (fluorescence_event.cpp).
#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "core/sampling.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

TEST(VonMisesFisher, PdfIntegratesToOne) {
  for (float kappa : {0.1f, 1.f, 5.f, 100.f, 1e4f}) {
    // ∫ p dω = 2π ∫_{-1}^{1} p(c) dc, midpoint rule.
    const int steps = 2000000;
    double sum = 0;
    for (int i = 0; i < steps; ++i) sum += vmf_pdf(float(-1.0 + (i + 0.5) * 2.0 / steps), kappa);
    EXPECT_NEAR(2 * M_PI * sum * 2.0 / steps, 1.0, 2e-3) << "kappa " << kappa;
  }
}

TEST(VonMisesFisher, SamplesHaveThePdfsMeanCosineAndAxis) {
  const Vec3 mu = normalize(Vec3{0.3f, -0.8f, 0.5f});
  for (float kappa : {0.1f, 2.8f, 50.f}) {
    // E[cos θ] = coth κ − 1/κ; σ of the sample mean from the sample spread.
    const double expected = 1.0 / std::tanh(double(kappa)) - 1.0 / kappa;
    Rng rng(test_seed(11), uint64_t(kappa * 10));
    const int n = 200000;
    double s = 0, s2 = 0, off_axis = 0;
    for (int i = 0; i < n; ++i) {
      const Vec3 w = sample_vmf(Point2{rng.uniform(), rng.uniform()}, mu, kappa);
      ASSERT_NEAR(length(w), 1.f, 1e-4f);
      const double c = dot(w, mu);
      s += c;
      s2 += c * c;
      off_axis += dot(w, normalize(Vec3{0.8f, 0.3f, 0.f}));  // ⟂ mu: mean 0
    }
    const double mean = s / n, sigma = std::sqrt((s2 / n - mean * mean) / n);
    EXPECT_NEAR(mean, expected, 4 * sigma + 1e-6) << "kappa " << kappa;
    EXPECT_NEAR(off_axis / n, 0.0, 4 * std::sqrt(1.0 / n)) << "kappa " << kappa;
  }
}
