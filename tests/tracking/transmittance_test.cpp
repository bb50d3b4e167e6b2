// Each transmittance estimator against exact optical depths: the mean of many
// estimates must lie within 4 standard errors (from the sample variance) of
// exp(-tau), per carried wavelength, from tau = 0.1 to 50.
//
// What can be checked at large tau: residual ratio tracking only tracks the
// residual above each cell's minimum, so its relative variance stays small and
// exp(-50) ~ 2e-22 is checked in relative terms. Ratio and delta (track-length)
// tracking have relative variance growing like e^tau (with a tight majorant a
// ratio-tracking estimate is almost always 0); for tau >= 20 no affordable
// sample count resolves exp(-tau), and the test checks only that their mean is
// within 4 standard errors plus 4/N of it (no bias upward of the resolution).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "slab_fixture.h"
#include "tracking/transmittance.h"
#include "test_seed.h"

using namespace chlorovdb;
using namespace chlorovdb::test;

namespace {

struct Stats {
  double mean[4] = {}, se[4] = {};
};

Stats estimate(const Slab& s, TransmittanceEstimator e, int n, uint64_t seed) {
  const SampledWavelengths lambda = four_wavelengths();
  const PreparedMedium pm = prepare(*s.medium, lambda);
  Rng rng(test_seed(seed), 0);
  double sum[4] = {}, sum2[4] = {};
  for (int i = 0; i < n; ++i) {
    const SampledSpectrum T = transmittance(s.ray, s.t_max, lambda, *s.medium, pm, e, rng);
    for (int l = 0; l < 4; ++l) {
      sum[l] += T[l];
      sum2[l] += double(T[l]) * T[l];
    }
    EXPECT_EQ(T[4], 0.f);  // lanes the path does not carry stay zero
  }
  Stats st;
  for (int l = 0; l < 4; ++l) {
    st.mean[l] = sum[l] / n;
    const double var = std::max(0.0, sum2[l] / n - st.mean[l] * st.mean[l]) * n / (n - 1);
    st.se[l] = std::sqrt(var / n);
  }
  return st;
}

// Relative tolerance for float rounding of a product of many factors.
constexpr double kRounding = 2e-4;

void expect_unbiased(const Slab& s, TransmittanceEstimator e, int n, uint64_t seed, bool relative) {
  const Stats st = estimate(s, e, n, seed);
  for (int l = 0; l < 4; ++l) {
    const double exact = std::exp(-s.tau[l]);
    double tolerance = 4.0 * st.se[l] + kRounding * exact;
    if (!relative) tolerance += 4.0 / n;
    EXPECT_NEAR(st.mean[l], exact, tolerance) << to_string(e) << " lane " << l << " tau " << s.tau[l]
                                              << " se " << st.se[l];
    if (relative && st.se[l] > 0) {
      EXPECT_LT(st.se[l], 0.25 * exact) << "too noisy to mean anything, lane " << l;
    }
  }
}

const TransmittanceEstimator kTracking[] = {TransmittanceEstimator::ratio, TransmittanceEstimator::residual_ratio,
                                            TransmittanceEstimator::delta};

// A grey, homogeneous absorber with optical depth tau along grey_slab_ray over [0, grey_slab_t_max].
Medium grey_homogeneous(double tau) {
  const float eps = 25000.f;  // L/(mol cm)
  MediumDesc d;
  d.solvent = Solvent::none();
  const double c = tau / 0.3 / (100.0 * std::log(10.0) * eps);
  d.pigments.push_back({{"grey", Spectrum::constant(eps), Spectrum::constant(0.f), 0.f}, Field::constant(float(c))});
  return Medium(d);
}
const Ray grey_slab_ray{{0.1f, 0.2f, 0.3f}, Vec3{0.6f, 0.f, 0.8f} * 2.f};  // 2 m per unit t
constexpr float grey_slab_t_max = 0.15f;                                   // 0.3 m

}  // namespace

TEST(Transmittance, ClosedFormIsExactInHomogeneousSlabs) {
  for (double tau : {0.1, 1.0, 5.0, 20.0, 50.0}) {
    const Slab s = homogeneous_slab(tau);
    const Stats st = estimate(s, TransmittanceEstimator::closed_form, 3, 1);
    for (int l = 0; l < 4; ++l) EXPECT_NEAR(st.mean[l], std::exp(-s.tau[l]), 1e-5 * std::exp(-s.tau[l]));
  }
}

TEST(Transmittance, TrackingIsUnbiasedInHomogeneousSlabs) {
  uint64_t seed = 10;
  for (double tau : {0.1, 1.0, 5.0, 20.0, 50.0})
    for (TransmittanceEstimator e : kTracking)
      expect_unbiased(homogeneous_slab(tau), e, 20000, seed++, tau <= 5.0 || e == TransmittanceEstimator::residual_ratio);
}

TEST(Transmittance, TrackingIsUnbiasedInPiecewiseLinearFields) {
  uint64_t seed = 100;
  for (double tau : {0.1, 1.0, 5.0})
    for (TransmittanceEstimator e : kTracking) expect_unbiased(piecewise_linear_slab(tau, rough_profile()), e, 20000, seed++, true);
  // Thick: a gentle field and a ray that stays inside the grid. Where the ray
  // crosses the grid's edge, a cell's minimum is the background 0 and residual
  // ratio tracking there is no better than ratio tracking.
  // 320000 rays: at tau = 50 residual ratio tracking's most absorbed lane (tau 60)
  // has a relative standard deviation of about 39 per ray (measured on 4e5 rays),
  // so 20000 rays put its standard error at the 25 % check itself, and that check
  // failed on 6 of 12 seeds whatever the roulette (also with none). At 80000 the
  // estimates are still so skewed that a sample without their rare large values
  // understates both the mean and its standard error: 2 of 200 seeds failed (session 6,
  // tools/seed_sweep.sh).
  const int n_thick = 320000;
  for (double tau : {20.0, 50.0})
    for (TransmittanceEstimator e : kTracking)
      expect_unbiased(piecewise_linear_slab(tau, gentle_profile(), 8, true), e, n_thick, seed++,
                      e == TransmittanceEstimator::residual_ratio);
}

TEST(Transmittance, SmallMajorantCellsAndConstantFieldsToo) {
  uint64_t seed = 200;
  const std::vector<double> flat(64, 1.0);
  for (double tau : {0.1, 2.0})
    for (TransmittanceEstimator e : kTracking) {
      expect_unbiased(piecewise_linear_slab(tau, rough_profile(), 1), e, 20000, seed++, true);
      expect_unbiased(piecewise_linear_slab(tau, flat, 3), e, 20000, seed++, true);
    }
}

TEST(Transmittance, GridMediaRunResidualRatioWhenAskedForClosedForm) {
  const Slab s = piecewise_linear_slab(1.0, rough_profile());
  expect_unbiased(s, TransmittanceEstimator::closed_form, 20000, 300, true);
}

TEST(Transmittance, UnboundedRaysAreExactlyOpaqueOrClear) {
  // No solvent: lanes beyond the pigment's table (eps = 0) see nothing at all.
  MediumDesc d;
  d.pigments.push_back({Pigment{"red", Spectrum::tabulated({600.f, 700.f}, {1000.f, 1000.f}),
                                Spectrum::constant(0.f), 0.f},
                        Field::constant(1e-6f)});
  const Medium m(d);
  const float lambda_nm[] = {650.f, 450.f}, pdf[] = {1.f, 1.f};
  const SampledWavelengths lambda = SampledWavelengths::from_values(lambda_nm, pdf, 2);
  const PreparedMedium pm = prepare(m, lambda);
  Rng rng(test_seed(1), 0);
  for (TransmittanceEstimator e : {TransmittanceEstimator::closed_form, TransmittanceEstimator::ratio,
                                   TransmittanceEstimator::residual_ratio, TransmittanceEstimator::delta}) {
    const SampledSpectrum T = transmittance({{0, 0, 0}, {1, 0, 0}}, kInfinity, lambda, m, pm, e, rng);
    EXPECT_EQ(T[0], 0.f) << to_string(e);
    EXPECT_EQ(T[1], 1.f) << to_string(e);
  }
}

TEST(Transmittance, EstimatorNamesRoundTrip) {
  for (TransmittanceEstimator e : {TransmittanceEstimator::delta, TransmittanceEstimator::ratio,
                                   TransmittanceEstimator::residual_ratio, TransmittanceEstimator::closed_form})
    EXPECT_EQ(transmittance_estimator_from_string(to_string(e)), e);
  EXPECT_FALSE(transmittance_estimator_from_string("auto"));
  EXPECT_EQ(automatic_transmittance_estimator(*homogeneous_slab(1.0).medium), TransmittanceEstimator::closed_form);
  EXPECT_EQ(automatic_transmittance_estimator(*piecewise_linear_slab(1.0, rough_profile()).medium),
            TransmittanceEstimator::residual_ratio);
}

TEST(Transmittance, ThickSegmentsAreRouletteBeforeTheirCollisions) {
  // A grey homogeneous medium, tau = 3 over one segment: ratio tracking's majorant is
  // exact there, so without the predicted roulette every estimate would be 0 or 1. The
  // roulette plays first with q = e^-3 / 0.25 (transmittance.cpp), so a non-zero estimate
  // is exactly 1/q: it survived the roulette, then met no collision. The mean stays e^-3.
  const double tau = 3.0;
  const Medium m = grey_homogeneous(tau);
  const SampledWavelengths lambda = four_wavelengths();
  const PreparedMedium pm = prepare(m, lambda);
  ASSERT_TRUE(pm.grey);
  const double inv_q = 0.25 / std::exp(-tau);
  Rng rng(test_seed(77), 0);
  const int n = 40000;
  int survivors = 0;
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    const float T = transmittance(grey_slab_ray, grey_slab_t_max, lambda, m, pm, TransmittanceEstimator::ratio, rng)[0];
    if (T != 0.f) {
      ASSERT_NEAR(T, inv_q, 1e-4 * inv_q);
      ++survivors;
    }
    sum += T;
    sum2 += double(T) * T;
  }
  EXPECT_GT(survivors, 0);
  const double mean = sum / n, se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / (n - 1));
  EXPECT_NEAR(mean, std::exp(-tau), 4.0 * se);
}

TEST(Transmittance, ExtremeOpticalDepthsStayFinite) {
  // Far beyond what float e^-tau resolves (its exp underflows near tau = 88, and at
  // tau ~ 80-88 the predicted roulette's q falls below the 24-bit resolution of a
  // uniform): every estimate must be finite, non-negative and, here, essentially 0.
  for (double tau : {60.0, 84.0, 87.0, 120.0, 1e4}) {
    const Medium m = grey_homogeneous(tau);
    const SampledWavelengths lambda = four_wavelengths();
    const PreparedMedium pm = prepare(m, lambda);
    Rng rng(test_seed(78), 0);
    for (TransmittanceEstimator e : kTracking)
      for (int i = 0; i < 20000; ++i) {
        const SampledSpectrum T = transmittance(grey_slab_ray, grey_slab_t_max, lambda, m, pm, e, rng);
        for (int l = 0; l < 4; ++l) {
          ASSERT_TRUE(std::isfinite(T[l]) && T[l] >= 0.f) << to_string(e) << " tau " << tau << ": " << T[l];
          // A survivor of both roulettes carries at most 4096 x 0.25 x (1/q <= 4096): far below any overflow.
          ASSERT_LE(T[l], 4096.f * 4096.f) << to_string(e) << " tau " << tau;
        }
      }
  }
}

TEST(Transmittance, GreyMediaTrackOneLaneForAll) {
  // The rough slab's grid, holding a grey absorber and grey particles instead of the
  // ramp pigment in water: prepare() finds it grey, every estimator then returns one
  // value on all carried lanes, unbiased against the exact optical depth.
  const Slab s = piecewise_linear_slab(2.0, rough_profile());
  double tau = 0;
  const std::shared_ptr<Medium> grey_medium = grey_medium_on(s, &tau);
  const Medium& grey = *grey_medium;
  ASSERT_GT(tau, 0.5);
  ASSERT_LT(tau, 5.0);

  const SampledWavelengths lambda = four_wavelengths();
  const PreparedMedium pm = prepare(grey, lambda);
  EXPECT_TRUE(pm.grey);
  EXPECT_FALSE(prepare(*s.medium, lambda).grey);  // the ramp pigment and water are not
  uint64_t seed = 300;
  for (TransmittanceEstimator e : kTracking) {
    Rng rng(test_seed(seed++), 0);
    double sum = 0, sum2 = 0;
    const int n = 20000;
    for (int i = 0; i < n; ++i) {
      const SampledSpectrum T = transmittance(s.ray, s.t_max, lambda, grey, pm, e, rng);
      for (int l = 1; l < 4; ++l) ASSERT_EQ(T[l], T[0]) << to_string(e);
      ASSERT_EQ(T[4], 0.f);
      sum += T[0];
      sum2 += double(T[0]) * T[0];
    }
    const double mean = sum / n, se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / (n - 1));
    EXPECT_NEAR(mean, std::exp(-tau), 4.0 * se + kRounding * std::exp(-tau)) << to_string(e) << " tau " << tau;
  }
}
