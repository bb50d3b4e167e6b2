// The standard-error layer against the spread of independent renders, and the
// error report that `converge` and `reference` print from it.
#include "scratch_dir.h"
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "analysis/analytic_slab.h"
#include "analysis/image_error.h"
#include "film/film.h"
#include "integrator/render.h"
#include "scene/scene_loader.h"
#include "render_image.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::render_image;
using chlorovdb::test::test_seed;

// R renders with different seeds. Per pixel p and channel, two unbiased estimates
// of Var(mean of n samples): the between-render variance s_b² (R - 1 dof) and the
// average of the R squared standard errors. Their difference D_p (summed over the
// channels of a pixel) has mean 0; pixels are independent, so mean_p D_p must lie
// within 4 standard errors (from the spread of D_p) of 0. The slab's
// fluorescence is sampled with 4 hero wavelengths, whose lanes are correlated:
// squaring lanes separately, or dividing by n instead of n - 1 at small n, fails this.
TEST(StandardError, AgreesWithTheSpreadOfIndependentRenders) {
  SlabCase slab = analytic_case("slab");
  slab.name = "stderr_spread";
  const Scene scene = load_scene(write_slab_scene(slab, chlorovdb::test::scratch_dir("analysis_tests")));
  const int R = 12, spp = 4;
  std::vector<Image> images;
  for (int r = 0; r < R; ++r) images.push_back(render_image(scene, test_seed(500 + r), spp));
  const size_t pixels = size_t(scene.settings.width) * scene.settings.height;
  std::vector<double> d(pixels, 0.0);
  double between_total = 0, stderr_total = 0;
  for (size_t p = 0; p < pixels; ++p)
    for (int c = 0; c < 3; ++c) {
      double sum = 0, sum2 = 0, se2 = 0;
      for (const Image& img : images) {
        const double v = img.find_layer("total")->pixels[3 * p + c];
        const double se = img.find_layer("total_stderr")->pixels[3 * p + c];
        sum += v, sum2 += v * v, se2 += se * se;
      }
      const double between = (sum2 - sum * sum / R) / (R - 1);
      d[p] += between - se2 / R;
      between_total += between;
      stderr_total += se2 / R;
    }
  double mean = 0, var = 0;
  for (double v : d) mean += v / double(pixels);
  for (double v : d) var += (v - mean) * (v - mean) / double(pixels - 1);
  const double sigma = std::sqrt(var / double(pixels));
  EXPECT_NEAR(mean, 0.0, 4 * sigma) << "between-render variance " << between_total << ", mean squared standard error "
                                    << stderr_total;
  EXPECT_GT(stderr_total, 0.0);
  std::printf("between-render variance / mean squared standard error = %.4f (4 sigma = %.4f)\n", between_total / stderr_total,
              4 * sigma * double(pixels) / stderr_total);
  // The layer means something: 4 sigma is well below the variance itself.
  EXPECT_LT(4 * sigma * double(pixels), 0.5 * stderr_total);
}

TEST(ImageError, ReportsTheReferencesOwnErrorAndDominantPixels) {
  Image ref, est;
  ref.width = est.width = 100;
  ref.height = est.height = 10;
  const size_t n = 1000 * 3;
  ref.layers = {{"total", {"R", "G", "B"}, std::vector<float>(n, 1.f)}, {"total_stderr", {"R", "G", "B"}, std::vector<float>(n, 0.1f)}};
  est.layers = {{"total", {"R", "G", "B"}, std::vector<float>(n, 1.f)}, {"total_stderr", {"R", "G", "B"}, std::vector<float>(n, 0.f)}};
  for (size_t i = 0; i < n; ++i) est.layers[0].pixels[i] = 1.f + ((i / 3) % 2 ? 0.05f : -0.05f);
  auto errors = image_errors(est, ref);
  ASSERT_EQ(errors.size(), 1u);  // the stderr layer is not compared
  EXPECT_NEAR(errors[0].reference_variance, 0.01, 1e-6);
  EXPECT_NEAR(errors[0].mse, 0.0025, 1e-6);
  EXPECT_NEAR(errors[0].top_pixel_share, 1.0 / 1000, 1e-6);  // uniform error: the worst pixel holds 1/1000
  EXPECT_NEAR(errors[0].top_pixel_share_rel, 1.0 / 1000, 1e-6);
  // The reference's term (0.01 / 1.01 per value) is 4x the measured relMSE (0.0025 / 1.01).
  EXPECT_NEAR(reference_rel_share(errors[0]), 4.0, 1e-4);
  EXPECT_NEAR(own_mse(errors[0]), 0.0025 - 0.01, 1e-6);
  EXPECT_NEAR(own_rel_mse(errors[0]), (0.0025 - 0.01) / (1 + kRelativeEpsilon), 1e-6);
  EXPECT_FALSE(relative_error_trustworthy(errors[0]));
  ASSERT_EQ(error_warnings(errors[0]).size(), 1u);
  EXPECT_NE(error_warnings(errors[0])[0].find("reference's own error"), std::string::npos);
  // One firefly: a single pixel holds most of the squared error.
  est.layers[0].pixels[0] = 30.f;
  ref.layers[1].pixels.assign(n, 0.f);
  errors = image_errors(est, ref);
  EXPECT_GT(errors[0].top_pixel_share, 0.9);
  EXPECT_GT(errors[0].top_pixel_share_rel, 0.9);  // the reference is not bright there: relMSE is dominated too
  EXPECT_FALSE(relative_error_trustworthy(errors[0]));
  ASSERT_EQ(error_warnings(errors[0]).size(), 1u);
  EXPECT_NE(error_warnings(errors[0])[0].find("worst"), std::string::npos);
  // A firefly of the reference (1000 where the rest is 1; the estimate reads 1 there, +-0.5
  // elsewhere): it holds nearly all the squared error, and ~0.4 % of relMSE, which weights
  // it by 1 / r^2. relMSE stays a trustworthy measure.
  for (size_t i = 0; i < n; ++i) est.layers[0].pixels[i] = 1.f + ((i / 3) % 2 ? 0.5f : -0.5f);
  for (size_t c = 0; c < 3; ++c) ref.layers[0].pixels[c] = 1000.f, est.layers[0].pixels[c] = 1.f;
  errors = image_errors(est, ref);
  EXPECT_GT(errors[0].top_pixel_share, 0.99);
  const double eps = kRelativeEpsilon * std::pow((999.0 * 3 + 3000.0) / 3000.0, 2);
  const double firefly = 3 * 999.0 * 999.0 / (1e6 + eps), rest = 999 * 3 * 0.25 / (1 + eps);
  EXPECT_NEAR(errors[0].top_pixel_share_rel, firefly / (firefly + rest), 1e-5);
  EXPECT_TRUE(relative_error_trustworthy(errors[0]));
  ASSERT_EQ(error_warnings(errors[0]).size(), 1u);  // on MSE only
  const ReferenceSelfError self = reference_self_error(ref, "total");
  EXPECT_TRUE(self.available);
  EXPECT_EQ(self.rms_stderr, 0.0);
  EXPECT_FALSE(reference_self_error(ref, "fluorescence").available);
}

// A liquid of bright pixels beside a dark set where the estimate's rare samples
// leave the same absolute error: relMSE weighs the dark pixels by 1 / eps, so
// they hold nearly all of it, and dim_pixel_share_rel says so.
TEST(ImageError, ReportsTheShareOfRelMseInDimPixels) {
  Image ref, est;
  ref.width = est.width = 100;
  ref.height = est.height = 1;
  ref.layers = {{"fluorescence", {"R"}, std::vector<float>(100, 0.f)}};
  for (size_t i = 0; i < 20; ++i) ref.layers[0].pixels[i] = 5.f;      // the liquid
  for (size_t i = 20; i < 100; ++i) ref.layers[0].pixels[i] = 0.01f;  // the set, under 10 % of the mean (1.008)
  est = ref;
  for (size_t i = 0; i < 100; ++i) est.layers[0].pixels[i] += (i % 2 ? 0.05f : -0.05f);
  const auto errors = image_errors(est, ref);
  ASSERT_EQ(errors.size(), 1u);
  const double mean = (20 * 5.0 + 80 * 0.01) / 100, eps = kRelativeEpsilon * mean * mean;
  const double bright = 20 * 0.0025 / (25 + eps), dim = 80 * 0.0025 / (1e-4 + eps);
  EXPECT_NEAR(errors[0].dim_pixel_share_rel, dim / (dim + bright), 1e-4);
  EXPECT_GT(errors[0].dim_pixel_share_rel, 0.99);
  // Errors in the liquid alone: no share in the dim pixels.
  est = ref;
  est.layers[0].pixels[3] += 1.f;
  EXPECT_EQ(image_errors(est, ref)[0].dim_pixel_share_rel, 0.0);
}
