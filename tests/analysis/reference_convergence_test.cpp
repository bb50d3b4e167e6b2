// The reference-convergence criterion of the benchmarks (analysis/reference_convergence.h)
// and the estimator it relies on: relMSE minus the reference's own term
// (own_rel_mse, analysis/image_error.h) measures the estimate's relMSE against the exact image.
#include "scratch_dir.h"
#include <gtest/gtest.h>

#include <cmath>

#include "analysis/analytic_slab.h"
#include "analysis/image_error.h"
#include "analysis/reference_convergence.h"
#include "film/film.h"
#include "integrator/render.h"
#include "scene/scene_loader.h"
#include "render_image.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::render_image;
using chlorovdb::test::test_seed;

namespace {

VariantError variant(const std::string& label, double rel_mse, double reference_rel_variance, double seconds) {
  VariantError v;
  v.label = label;
  v.error.rel_mse = rel_mse;
  v.error.reference_rel_variance = reference_rel_variance;
  v.seconds = seconds;
  return v;
}

}  // namespace

TEST(ReferenceConvergence, ComparesTheReferencesTermWithTheBestVariantsOwnRelMse) {
  // Own relMSE: a 0.5 - 0.01 = 0.49, b 0.2 - 0.01 = 0.19 (the best), c 1.0 - 0.01.
  const std::vector<VariantError> v = {variant("a", 0.5, 0.01, 3), variant("b", 0.2, 0.01, 3), variant("c", 1.0, 0.01, 3)};
  const ReferenceCheck c = check_reference(0.01, v, 0);
  EXPECT_EQ(c.best_label, "b");
  EXPECT_NEAR(c.best_own_rel_mse, 0.19, 1e-12);
  EXPECT_NEAR(c.share, 0.01 / 0.19, 1e-12);
  EXPECT_TRUE(c.met);  // 5.3 % <= 10 %
  const ReferenceCheck tight = check_reference(0.05, v, 0);
  EXPECT_FALSE(tight.met);  // 26 % of b's
  // relMSE ∝ 1 / spp of the reference: 1000 spp at share 0.05 / 0.19 reach 10 % at 1000 · 2.63 spp.
  EXPECT_EQ(reference_spp_needed(1000, tight, 1 << 20), int(std::ceil(1000 * (0.05 / 0.19) / kReferenceShareTarget)));
  EXPECT_EQ(reference_spp_needed(1000, tight, 2000), 2000);  // the cap
  EXPECT_EQ(reference_spp_needed(1000, c, 1 << 20), 1000);   // met: no more samples
}

TEST(ReferenceConvergence, PredictsTheOwnRelMseAtTheFullBudgetFromAPilot) {
  // A pilot at 0.5 s predicts own relMSE ∝ 1 / time at the 4 s budget: 0.8 · 0.5 / 4 = 0.1.
  const ReferenceCheck c = check_reference(0.02, {variant("pilot", 0.81, 0.01, 0.5)}, 4);
  EXPECT_NEAR(c.best_own_rel_mse, 0.1, 1e-12);
  EXPECT_NEAR(c.share, 0.2, 1e-12);
  EXPECT_EQ(reference_spp_needed(512, c, 1 << 20), 1024);
}

TEST(ReferenceConvergence, AReferenceTermAsLargeAsTheMeasuredErrorAsksForTheCap) {
  // Own relMSE <= 0: the reference's term is the whole measured error.
  const ReferenceCheck c = check_reference(0.3, {variant("a", 0.3, 0.3, 1)}, 0);
  EXPECT_FALSE(c.met);
  EXPECT_TRUE(std::isinf(c.share));
  EXPECT_EQ(reference_spp_needed(256, c, 4096), 4096);
  EXPECT_THROW(check_reference(0.1, {}, 0), std::invalid_argument);
}

// The estimator the benchmarks rank on. The analytic slab's pixels are independent
// replicates with an exact value mu. Per pixel p, D_p = own relMSE term against a noisy
// reference r (independent seed, twice the estimate's samples: its term is a third of the
// measured error) minus the relMSE term against mu. mean_p D_p must be 0 within 4
// standard errors (from the spread of D_p); the uncorrected rel_mse must not be: it
// carries the reference's term, many standard errors away. The weights 1/(r² + eps) use
// the noisy r, which leaves a relative bias of about 3 × the estimate's own relMSE
// (~3 % at 256 spp here, about one standard error): the correction is first order, so the
// estimate has to be well resolved, as the benchmarks' are where they are trustworthy.
TEST(ReferenceConvergence, OwnRelMseAgainstANoisyReferenceMatchesTheErrorAgainstTheExactImage) {
  SlabCase slab = analytic_case("slab");
  slab.name = "own_rel_mse";
  slab.resolution = 48;
  const Scene scene = load_scene(write_slab_scene(slab, chlorovdb::test::scratch_dir("analysis_tests")));
  const Image truth = slab_reference_image(slab, scene);
  const int spp = 256;
  const Image estimate = render_image(scene, test_seed(71), spp);
  const Image reference = render_image(scene, test_seed(1000071), 2 * spp);
  const LayerError noisy = *find_error(image_errors(estimate, reference), "total");
  const LayerError exact = *find_error(image_errors(estimate, truth), "total");
  EXPECT_EQ(exact.reference_rel_variance, 0.0);  // the analytic image has no standard-error layer
  ASSERT_GT(noisy.reference_rel_variance, 0.0);

  // Per-pixel terms, with the weights image_errors uses (eps from each reference's own mean).
  const ImageLayer& x = *estimate.find_layer("total");
  const ImageLayer& r = *reference.find_layer("total");
  const ImageLayer& se = *reference.find_layer("total_stderr");
  const ImageLayer& mu = *truth.find_layer("total");
  auto eps_of = [](const ImageLayer& l) {
    double m = 0;
    for (float v : l.pixels) m += v / double(l.pixels.size());
    return std::max(kRelativeEpsilon * m * m, 1e-30);
  };
  const double eps_r = eps_of(r), eps_mu = eps_of(mu);
  const size_t pixels = x.pixels.size() / 3;
  std::vector<double> d(pixels, 0.0);
  for (size_t i = 0; i < x.pixels.size(); ++i) {
    const double dr = double(x.pixels[i]) - r.pixels[i], dm = double(x.pixels[i]) - mu.pixels[i];
    const double s2 = double(se.pixels[i]) * se.pixels[i];
    d[i / 3] += (dr * dr - s2) / (double(r.pixels[i]) * r.pixels[i] + eps_r) - dm * dm / (double(mu.pixels[i]) * mu.pixels[i] + eps_mu);
  }
  double mean = 0, var = 0;
  for (double v : d) mean += v / double(pixels);
  for (double v : d) var += (v - mean) * (v - mean) / double(pixels - 1);
  const double sigma = std::sqrt(var / double(pixels)) / 3;  // of the mean over pixels and channels
  // The per-pixel sums agree with image_errors' layer means.
  EXPECT_NEAR(mean / 3, own_rel_mse(noisy) - exact.rel_mse, 1e-6 * exact.rel_mse);
  std::printf("own relMSE %.4e, exact %.4e, measured %.4e (reference's share %.2f), 4 sigma %.2e\n", own_rel_mse(noisy),
              exact.rel_mse, noisy.rel_mse, reference_rel_share(noisy), 4 * sigma);
  EXPECT_NEAR(own_rel_mse(noisy), exact.rel_mse, 4 * sigma);
  EXPECT_GT(std::abs(noisy.rel_mse - exact.rel_mse), 4 * sigma);  // the correction matters here
}
