// The continuation guide's direction density (fluorescence/continuation_guide.h):
// equal-area bins, a pdf that integrates to one and matches its samples.
#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "fluorescence/continuation_guide.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

namespace {

// One cell over the unit box whose histogram puts most weight in a few bins.
ContinuationGuide peaked_guide(float uniform_share) {
  std::vector<float> w(kDirectionBins, 0.f);
  w[size_t(direction_bin(normalize(Vec3{1, 0.2f, -0.3f})))] = 50.f;
  w[size_t(direction_bin(Vec3{0, 0, 1}))] = 20.f;
  for (int b = 0; b < kDirectionBins; b += 7) w[size_t(b)] += 1.f;
  return ContinuationGuide(Bounds3{{0, 0, 0}, {1, 1, 1}}, {1, 1, 1}, {w}, uniform_share);
}

}  // namespace

TEST(ContinuationGuide, DirectionsInABinMapBackToIt) {
  Rng rng(test_seed(1), 0);
  for (int bin = 0; bin < kDirectionBins; ++bin)
    for (int k = 0; k < 4; ++k) {
      // Stay off the bin's edges, where float rounding may pick the neighbour.
      const Point2 u{0.01f + 0.98f * rng.uniform(), 0.01f + 0.98f * rng.uniform()};
      const Vec3 w = direction_in_bin(bin, u);
      ASSERT_NEAR(length(w), 1.f, 1e-5f);
      ASSERT_EQ(direction_bin(w), bin) << "u = " << u.x << ", " << u.y;
    }
}

TEST(ContinuationGuide, BinsHaveEqualSolidAngle) {
  // Uniform directions fall into the 512 bins with equal probability: a
  // chi-square over the bins stays below its 4σ bound (dof 511: mean 511, σ 32).
  constexpr int kPerBin = 200;
  std::vector<int> counts(kDirectionBins, 0);
  Rng rng(test_seed(2), 0);
  for (int i = 0; i < kPerBin * kDirectionBins; ++i)
    ++counts[size_t(direction_bin(sample_uniform_sphere(Point2{rng.uniform(), rng.uniform()})))];
  double chi2 = 0;
  for (int c : counts) chi2 += (c - kPerBin) * double(c - kPerBin) / kPerBin;
  EXPECT_LT(chi2, 511 + 4 * std::sqrt(2.0 * 511));
  EXPECT_GT(chi2, 511 - 4 * std::sqrt(2.0 * 511));
}

TEST(ContinuationGuide, PdfIntegratesToOneAndIsBoundedBelowByTheUniformShare) {
  const ContinuationGuide guide = peaked_guide(0.3f);
  const Vec3 x{0.5f, 0.5f, 0.5f};
  // ∫ pdf dω by uniform directions: mean of pdf / (1/4π).
  Rng rng(test_seed(3), 0);
  double sum = 0, sum2 = 0;
  constexpr int n = 400000;
  float lowest = 1e9f;
  for (int i = 0; i < n; ++i) {
    const Vec3 w = sample_uniform_sphere(Point2{rng.uniform(), rng.uniform()});
    const double v = guide.pdf(x, w) / uniform_sphere_pdf();
    sum += v, sum2 += v * v;
    lowest = std::min(lowest, guide.pdf(x, w));
  }
  const double mean = sum / n, sigma = std::sqrt((sum2 / n - mean * mean) / n);
  EXPECT_NEAR(mean, 1.0, 4 * sigma);
  EXPECT_GE(lowest, 0.3f * uniform_sphere_pdf() * (1 - 1e-5f));
  // Outside the grid and with no guide: uniform.
  EXPECT_FLOAT_EQ(guide.pdf(Vec3{2, 0, 0}, Vec3{0, 0, 1}), uniform_sphere_pdf());
  EXPECT_FLOAT_EQ(ContinuationGuide().pdf(x, Vec3{0, 0, 1}), uniform_sphere_pdf());
}

TEST(ContinuationGuide, SamplesFollowTheirPdf) {
  // E[f(w) / pdf(w)] over guided samples = ∫ f dω, for f the indicator of a cap
  // around the peak (most samples) and of one on the far side (few samples).
  const ContinuationGuide guide = peaked_guide(0.3f);
  const Vec3 x{0.5f, 0.5f, 0.5f};
  const Vec3 axes[2] = {normalize(Vec3{1, 0.2f, -0.3f}), normalize(Vec3{-0.4f, -1, 0.1f})};
  constexpr float kCosCap = 0.9f;
  const double exact = 2 * M_PI * (1 - kCosCap);
  for (const Vec3& axis : axes) {
    Rng rng(test_seed(4), 0);
    double sum = 0, sum2 = 0;
    constexpr int n = 400000;
    for (int i = 0; i < n; ++i) {
      const DirectionSample s = guide.sample(x, rng.uniform(), Point2{rng.uniform(), rng.uniform()});
      ASSERT_FLOAT_EQ(s.pdf, guide.pdf(x, s.w));
      const double v = dot(s.w, axis) > kCosCap ? 1.0 / s.pdf : 0.0;
      sum += v, sum2 += v * v;
    }
    const double mean = sum / n, sigma = std::sqrt((sum2 / n - mean * mean) / n);
    EXPECT_NEAR(mean, exact, 4 * sigma) << "cap around " << axis.x << ", " << axis.y << ", " << axis.z;
  }
}

TEST(ContinuationGuide, CellsAreFoundByPositionAndEmptyCellsAreUniform) {
  std::vector<std::vector<float>> w(8, std::vector<float>(kDirectionBins, 0.f));
  w[7][0] = 1.f;  // only the (1, 1, 1) cell learned anything
  const ContinuationGuide guide(Bounds3{{0, 0, 0}, {2, 2, 2}}, {2, 2, 2}, w, 0.5f);
  EXPECT_EQ(guide.cell_of(Vec3{0.5f, 0.5f, 0.5f}), 0);
  EXPECT_EQ(guide.cell_of(Vec3{1.5f, 0.5f, 0.5f}), 1);
  EXPECT_EQ(guide.cell_of(Vec3{1.5f, 1.5f, 1.5f}), 7);
  EXPECT_EQ(guide.cell_of(Vec3{2.5f, 1.5f, 1.5f}), -1);
  EXPECT_FLOAT_EQ(guide.pdf(Vec3{0.5f, 0.5f, 0.5f}, Vec3{0, 0, -1}), uniform_sphere_pdf());
  const Vec3 in_bin0 = direction_in_bin(0, Point2{0.5f, 0.5f});
  EXPECT_FLOAT_EQ(guide.pdf(Vec3{1.5f, 1.5f, 1.5f}, in_bin0),
                  0.5f * uniform_sphere_pdf() + 0.5f * kDirectionBins * uniform_sphere_pdf());
}
