// Error metrics, power-law fits, SVG plots and the sample-weighted mean merge.
#include <gtest/gtest.h>

#include <cmath>

#include "analysis/image_error.h"
#include "analysis/loglog_fit.h"
#include "analysis/progressive.h"
#include "analysis/svg_plot.h"

using namespace chlorovdb;

namespace {

Image flat_image(int w, int h, std::vector<std::pair<std::string, float>> layers) {
  Image image;
  image.width = w;
  image.height = h;
  for (auto& [name, v] : layers) image.layers.push_back({name, {"R", "G", "B"}, std::vector<float>(size_t(w) * h * 3, v)});
  return image;
}

}  // namespace

TEST(ImageError, MetricsOfAKnownDifference) {
  Image ref = flat_image(4, 2, {{"total", 2.f}, {"fluorescence", 1.f}});
  Image est = flat_image(4, 2, {{"total", 2.f}, {"fluorescence", 1.f}, {"extra", 0.f}});
  est.layers[0].pixels[0] = 3.f;  // one value off by 1 out of 24
  const auto errors = image_errors(est, ref);
  ASSERT_EQ(errors.size(), 2u);  // "extra" is not in the reference
  const LayerError* t = find_error(errors, "total");
  ASSERT_NE(t, nullptr);
  EXPECT_NEAR(t->mse, 1.0 / 24, 1e-12);
  EXPECT_NEAR(t->rmse, std::sqrt(1.0 / 24), 1e-12);
  EXPECT_NEAR(t->bias, 1.0 / 24, 1e-12);
  EXPECT_NEAR(t->rel_mse, 1.0 / (4.0 + kRelativeEpsilon * 4.0) / 24, 1e-12);
  EXPECT_EQ(find_error(errors, "fluorescence")->mse, 0.0);
  EXPECT_THROW(image_errors(flat_image(2, 2, {{"total", 1.f}}), ref), std::invalid_argument);
}

TEST(LogLogFit, RecoversAnExactPowerLaw) {
  std::vector<double> x, y;
  for (double n : {1.0, 4.0, 16.0, 64.0, 256.0}) {
    x.push_back(n);
    y.push_back(3.0 * std::pow(n, -0.5));
  }
  x.push_back(0.0);  // ignored
  y.push_back(1.0);
  const PowerFit fit = fit_power_law(x, y);
  EXPECT_EQ(fit.points, 5);
  EXPECT_NEAR(fit.exponent, -0.5, 1e-12);
  EXPECT_NEAR(fit.coefficient, 3.0, 1e-12);
  EXPECT_NEAR(fit.r2, 1.0, 1e-12);
  EXPECT_LT(fit_power_law(std::vector<double>{1.0}, std::vector<double>{1.0}).points, 2);
}

TEST(LogLogFit, FromXMinFitsOnlyTheTail) {
  // Flat up to 16 (a rare path not yet sampled), then n^-1: the whole range is
  // flatter than -1, the tail from 16 on is exactly -1.
  std::vector<double> x, y;
  for (double n = 1; n <= 512; n *= 2) {
    x.push_back(n);
    y.push_back(n < 16 ? 1.0 : 16.0 / n);
  }
  EXPECT_GT(fit_power_law(x, y).exponent, -0.8);
  const PowerFit tail = fit_power_law(x, y, 16);
  EXPECT_EQ(tail.points, 6);
  EXPECT_NEAR(tail.exponent, -1.0, 1e-12);
  EXPECT_NEAR(tail.coefficient, 16.0, 1e-9);
}

TEST(LogLogFit, MeanExponentOverRunsHasTheSpreadOfTheRuns) {
  // Exponents -0.9, -1.0, -1.1 (+ one unusable fit): mean -1, sample sd 0.1, se 0.1/sqrt(3).
  std::vector<PowerFit> fits;
  for (double k : {-0.9, -1.0, -1.1}) fits.push_back(PowerFit{k, 1.0, 1.0, 5});
  fits.push_back(PowerFit{7.0, 1.0, 1.0, 1});
  const MeanOverRuns r = mean_exponent(fits);
  EXPECT_EQ(r.runs, 3);
  EXPECT_NEAR(r.mean, -1.0, 1e-12);
  EXPECT_NEAR(r.standard_error, 0.1 / std::sqrt(3.0), 1e-12);
  EXPECT_EQ(mean_exponent(std::vector<PowerFit>{PowerFit{-0.5, 1.0, 1.0, 3}}).standard_error, 0.0);
  EXPECT_EQ(mean_exponent(std::vector<PowerFit>{}).runs, 0);
}

TEST(SvgPlot, WritesOnePolylinePerSeriesAndTheGuide) {
  LogLogPanel p{"t", "x", "y", {{"a", {1, 10, 100}, {1, 0.3, 0.1}}, {"b", {1, 10}, {2, 0.5}}}, -0.5};
  const std::string svg = loglog_svg({p, p});
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  size_t polylines = 0;
  for (size_t at = 0; (at = svg.find("<polyline", at)) != std::string::npos; ++at) ++polylines;
  EXPECT_EQ(polylines, 4u);
  EXPECT_NE(svg.find("stroke-dasharray"), std::string::npos);
  EXPECT_NE(svg.find("slope -1/2"), std::string::npos);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
}

