// The regression statistic on synthetic data: same-distribution estimates pass,
// a 5 % shift of one pixel fails, and the t p-value matches known quantiles.
#include <gtest/gtest.h>

#include "core/rng.h"
#include "regression.h"
#include "test_seed.h"

using namespace chlorovdb;
using namespace chlorovdb::regression;

namespace {

// Batches of a w x h image whose every statistic is `mean` plus noise of std `sigma`;
// `shift` scales pixel (0, 0). With `heavy`, each of a batch's `spp` samples is, with
// probability 2 %, a firefly 50x the mean (what liquid in glass under UV gives).
Estimate synthetic(uint64_t seed, int batches, double sigma, double shift, bool heavy = false, int spp = 1) {
  const int w = 16, h = 8;
  BatchAccumulator acc(w, h);
  Rng rng(seed, 0);
  for (int b = 0; b < batches; ++b) {
    std::vector<double> xyz(size_t(w) * h * 3);
    for (size_t i = 0; i < xyz.size(); ++i) {
      double s = 0;
      for (int k = 0; k < 12; ++k) s += rng.uniform();
      xyz[i] = 1.0 + sigma * (s - 6.0);
      if (heavy)
        for (int k = 0; k < spp; ++k)
          if (rng.uniform() < 0.02f) xyz[i] += 50.0 / spp;
      if (i < 3) xyz[i] *= shift;
    }
    acc.add_batch(xyz);
  }
  Estimate e = acc.estimate();
  e.spp_per_batch = spp;
  return e;
}

}  // namespace

TEST(RegressionStatistic, StudentTPValueMatchesTables) {
  EXPECT_NEAR(student_t_p(2.0, 1e6), 0.0455, 1e-4);   // normal limit
  EXPECT_NEAR(student_t_p(2.228, 10), 0.05, 1e-3);    // t_{0.975, 10}
  EXPECT_NEAR(student_t_p(4.587, 10), 0.001, 5e-5);   // t_{0.9995, 10}
  EXPECT_NEAR(student_t_p(0.0, 5), 1.0, 1e-12);
}

TEST(RegressionStatistic, SameDistributionPassesAcrossSeeds) {
  int failures = 0;
  for (uint64_t s = 0; s < 20; ++s)
    failures += compare(synthetic(test::test_seed(100 + s), 32, 0.05, 1.0),
                        synthetic(test::test_seed(200 + s), 64, 0.05, 1.0), 1e-3).failed();
  EXPECT_LE(failures, 1) << "false alarms out of 20 at a family-wise alpha of 1e-3";
}

TEST(RegressionStatistic, FivePercentChangeOfOnePixelFails) {
  const Comparison c = compare(synthetic(test::test_seed(1), 32, 0.02, 1.05), synthetic(test::test_seed(2), 64, 0.02, 1.0), 1e-3);
  EXPECT_TRUE(c.failed());
  EXPECT_LT(c.worst, 3u) << "the shifted pixel is the worst statistic";
}

// A short render that misses the reference's rare huge samples is not a regression.
TEST(RegressionStatistic, HeavyTailsDoNotFailTheSameRenderer) {
  int failures = 0;
  for (uint64_t s = 0; s < 20; ++s)
    failures += compare(synthetic(test::test_seed(300 + s), 64, 0.05, 1.0, true, 2),
                        synthetic(test::test_seed(400 + s), 64, 0.05, 1.0, true, 16), 1e-3).failed();
  EXPECT_LE(failures, 1) << "false alarms out of 20 with rare samples 50x the mean (the CI plan: 64 x 2 spp "
                            "against 64 x 16 spp)";
}

TEST(RegressionStatistic, BlackPixelsMustAgree) {
  Estimate a = synthetic(test::test_seed(3), 8, 0.0, 1.0), b = a;
  EXPECT_FALSE(compare(a, b, 1e-3).failed());
  b.mean[5] += 1e-3;
  EXPECT_TRUE(compare(a, b, 1e-3).failed());
}
