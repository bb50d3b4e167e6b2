#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <variant>

#include "spectra/csv.h"
#include "spectra/library.h"
#include "spectra/spectrum.h"

using namespace chlorovdb;

namespace {

void expect_table_matches_csv(const std::string& file, const std::string& column) {
  const CsvTable table = read_csv_table(spectra_dir() / file);
  const Spectrum s = load_spectrum_csv(spectra_dir() / file, column);
  const std::vector<float> v = table.values(column);
  for (size_t i = 0; i < v.size(); ++i) {
    const float lambda = float(table.wavelength_nm[i]);
    ASSERT_EQ(s(lambda), v[i]) << file << " row at " << lambda << " nm";
    if (i + 1 < v.size()) {
      // Between rows: linear interpolation (at the float nearest the midpoint).
      const double next = float(table.wavelength_nm[i + 1]);
      const float mid = 0.5f * (lambda + float(next));
      const double t = (mid - lambda) / (next - lambda);
      ASSERT_NEAR(s(mid), (1 - t) * v[i] + t * v[i + 1], 1e-5 * std::max(1.f, std::fabs(v[i]) + std::fabs(v[i + 1])))
          << file << " between rows at " << mid << " nm";
    }
  }
}

}  // namespace

TEST(Spectrum, TableLookupsEqualCsvRowsUniformStep) { expect_table_matches_csv("cie_d65.csv", "value"); }

TEST(Spectrum, TableLookupsEqualCsvRowsIrregularStep) {
  expect_table_matches_csv("chlorophyll_a_molar_extinction.csv", "value");
}

// locate()'s guide (one index per half average spacing) walked to the segment a
// binary search finds, on a table whose spacing runs from 0.01 to 50 nm: at every knot,
// the floats beside it, and 20 000 points between.
TEST(Spectrum, IrregularTableLocatesTheSegmentABinarySearchFinds) {
  std::vector<float> lambda{300.f}, value{0.f};
  const float steps[] = {0.01f, 50.f, 0.3f, 0.01f, 0.01f, 7.f, 0.5f, 25.f, 0.02f, 1.f};
  for (int r = 0; r < 30; ++r) {
    lambda.push_back(lambda.back() + steps[r % 10]);
    value.push_back(float(r % 7));
  }
  const Spectrum s = Spectrum::tabulated(lambda, value);
  const auto& table = std::get<Spectrum::Tabulated>(s.representation());
  ASSERT_FALSE(table.guide.empty());
  const auto expect_binary_search = [&](float l) {
    const auto at = table.locate(l);
    ASSERT_TRUE(at.has_value()) << l;
    const size_t i = std::min(size_t(std::upper_bound(lambda.begin(), lambda.end(), l) - lambda.begin()) - 1,
                              lambda.size() - 2);
    ASSERT_EQ(at->i, i) << l << " nm";
    ASSERT_EQ(at->x, (l - lambda[i]) / (lambda[i + 1] - lambda[i])) << l << " nm";
  };
  for (size_t i = 0; i < lambda.size(); ++i) {
    expect_binary_search(lambda[i]);
    if (i > 0) expect_binary_search(std::nextafter(lambda[i], 0.f));
    if (i + 1 < lambda.size()) expect_binary_search(std::nextafter(lambda[i], 1e9f));
  }
  for (int k = 0; k <= 20000; ++k)
    expect_binary_search(std::min(lambda.front() + (lambda.back() - lambda.front()) * float(k) / 20000.f, lambda.back()));
  EXPECT_FALSE(table.locate(std::nextafter(lambda.front(), 0.f)).has_value());
  EXPECT_FALSE(table.locate(std::nextafter(lambda.back(), 1e9f)).has_value());
}

TEST(Spectrum, TabulatedIsZeroOutsideTheTable) {
  const Spectrum chl = named_spectrum("chlorophyll_a");  // 219.81–700 nm
  EXPECT_GT(chl(700.f), 0.f);
  EXPECT_EQ(chl(700.01f), 0.f);  // never extrapolated: chlorophyll absorption beyond 700 nm is zero
  EXPECT_EQ(chl(750.f), 0.f);
  EXPECT_EQ(chl(219.8f), 0.f);
  EXPECT_EQ(chl(std::nanf("")), 0.f);
  EXPECT_EQ(chl.support_max(), 700.f);
}

TEST(Spectrum, SupportSkipsZeroEnds) {
  const Spectrum s = Spectrum::tabulated({400, 410, 420, 430, 440}, {0, 0, 1, 0, 0});
  EXPECT_EQ(s.support_min(), 410.f);
  EXPECT_EQ(s.support_max(), 430.f);
}

TEST(Spectrum, TabulatedValidation) {
  EXPECT_THROW(Spectrum::tabulated({400}, {1}), std::invalid_argument);
  EXPECT_THROW(Spectrum::tabulated({400, 500}, {1}), std::invalid_argument);
  EXPECT_THROW(Spectrum::tabulated({500, 400}, {1, 1}), std::invalid_argument);
  EXPECT_THROW(Spectrum::tabulated({400, 400}, {1, 1}), std::invalid_argument);
  EXPECT_THROW(Spectrum::tabulated({400, 500}, {1, NAN}), std::invalid_argument);
}

TEST(Spectrum, TabulatedIntegralIsExact) {
  const Spectrum s = Spectrum::tabulated({400, 410, 430}, {1, 3, 0}).scaled(2.f);
  // Trapezoids: 10·(1+3)/2 + 20·(3+0)/2 = 50, times scale 2.
  EXPECT_FLOAT_EQ(s.integral(0, 1000), 100.f);
  // Partial segments: [405, 420] = 5·(2+3)/2 + 10·(3+1.5)/2 = 12.5 + 22.5 = 35.
  EXPECT_FLOAT_EQ(s.integral(405, 420), 70.f);
  EXPECT_FLOAT_EQ(s.integral(420, 405), -70.f);
  EXPECT_FLOAT_EQ(s.max_value(), 6.f);
}

TEST(Spectrum, ConstantIntegralAndScale) {
  const Spectrum c = Spectrum::constant(0.5f).scaled(4.f);
  EXPECT_FLOAT_EQ(c(123.f), 2.f);
  EXPECT_FLOAT_EQ(c.integral(400, 700), 600.f);
}

TEST(Spectrum, BlackbodyPeaksAtWienWavelengthWithValueOne) {
  for (float T : {3000.f, 5778.f, 6500.f}) {
    const Spectrum bb = Spectrum::blackbody(T);
    const float wien_nm = 2.897771955e-3f / T * 1e9f;
    float best = 0, best_lambda = 0;
    for (float l = 250; l <= 1200; l += 0.05f)
      if (bb(l) > best) best = bb(l), best_lambda = l;
    EXPECT_NEAR(best, 1.f, 1e-5f) << T;
    EXPECT_NEAR(best_lambda, wien_nm, 0.1f) << T;
    EXPECT_LT(bb(wien_nm - 50), 1.f);
    EXPECT_LT(bb(wien_nm + 50), 1.f);
  }
  // 6500 K peaks at 446 nm, inside the renderer's range.
  EXPECT_NEAR(Spectrum::blackbody(6500).max_value(), 1.f, 1e-6f);
}

TEST(Spectrum, BlackbodyIntegralMatchesFineRiemannSum) {
  const Spectrum bb = Spectrum::blackbody(4000);
  double sum = 0;
  const double h = 0.01;
  for (double l = 380 + h / 2; l < 780; l += h) sum += bb(float(l)) * h;
  EXPECT_NEAR(bb.integral(380, 780), sum, 1e-5 * sum);
}

TEST(Spectrum, GaussianIntegral) {
  const float mean = 685, sigma = 10.6f, peak = 3;
  const Spectrum g = Spectrum::gaussian(mean, sigma, peak);
  EXPECT_FLOAT_EQ(g(mean), peak);
  EXPECT_NEAR(g(mean + sigma), peak * std::exp(-0.5f), 1e-5f * peak);  // mean + sigma rounds in float
  EXPECT_NEAR(g.integral(mean - 10 * sigma, mean + 10 * sigma), peak * sigma * std::sqrt(2 * M_PI), 1e-4);
  // One sigma either side: erf(1/√2) = 0.682689...
  EXPECT_NEAR(g.integral(mean - sigma, mean + sigma), 0.6826895 * peak * sigma * std::sqrt(2 * M_PI), 1e-4);
}

TEST(Spectrum, SampleFillsOnlyCarriedLanes) {
  const Spectrum c = Spectrum::constant(2.f);
  const float lambda[3] = {400, 500, 600}, pdf[3] = {1, 1, 1};
  const SampledSpectrum v = c.sample(SampledWavelengths::from_values(lambda, pdf, 3));
  for (int i = 0; i < kMaxWavelengths; ++i) EXPECT_EQ(v[i], i < 3 ? 2.f : 0.f);
}
