// The stopping rule of `render --target-error` (film/stopping_rule.h): looks only
// at powers of two, and the error it stops at is within its target when measured
// against the exact image of an analytic slab.
#include "scratch_dir.h"
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "analysis/analytic_slab.h"
#include "film/stopping_rule.h"
#include "integrator/render.h"
#include "scene/scene_loader.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

TEST(StoppingRule, LooksOnlyAtPowersOfTwoFromTheMinimum) {
  EXPECT_FALSE(is_look(8, 16));
  EXPECT_TRUE(is_look(16, 16));
  EXPECT_FALSE(is_look(24, 16));
  EXPECT_TRUE(is_look(1024, 16));
  EXPECT_FALSE(is_look(0, 0));
  Film film(4, 4, {"total"}, ColorSpace::sRGB);
  StoppingRule rule;
  rule.time_limit_s = 2.0;
  EXPECT_EQ(check_stop(rule, film, 3, 1.0).reason, StopReason::none);
  EXPECT_EQ(check_stop(rule, film, 3, 2.5).reason, StopReason::time_limit);
  EXPECT_THROW(relative_standard_error(film, 4, PixelRegion{0, 0, 5, 4}), std::invalid_argument);
  EXPECT_TRUE(std::isinf(relative_standard_error(film, 4, std::nullopt)));  // black
}

// Per target: render the slab (every pixel an independent replicate of one exact
// value) until the rule stops it, then measure the relative RMS error against the
// exact image. e(n) ~ c / sqrt(n) is looked at every factor 2, so when it fires the
// true error lies in [target / sqrt(2), target] up to the noise of the two
// estimates: each is an RMS over 16 x 16 pixels (>= 256 independent terms even if a
// pixel's channels were fully correlated), relative sd <= sqrt(1 / (2 * 256)) =
// 0.044 each, 0.0625 for the ratio; 4 sigma = 25 %. The stopped image's mean over
// pixels must also match the exact value within 4 sigma (no bias from stopping).
TEST(StoppingRule, AchievedErrorIsWithinTheTarget) {
  SlabCase slab = analytic_case("slab");
  slab.name = "stopping_rule";
  const Scene scene = load_scene(write_slab_scene(slab, chlorovdb::test::scratch_dir("analysis_tests")));
  const Image truth = slab_reference_image(slab, scene);
  const ImageLayer& r = truth.layers[0];
  int k = 0;
  for (const double target : {0.25, 0.12}) {  // per-sample relative error ~3.2: 256 and 1024 spp
    Film film(scene.settings.width, scene.settings.height, film_layer_names(), scene.settings.color_space);
    StoppingRule rule;
    rule.target_relative_error = target;
    RenderOptions o;
    o.spp = 1 << 14;
    o.seed = test_seed(900 + k++);
    double estimate = 0;
    o.stop_after_pass = [&](const Film& f, int done) {
      const StopDecision d = check_stop(rule, f, done, 0);
      if (d.relative_error >= 0) estimate = d.relative_error;
      return d.reason != StopReason::none;
    };
    const RenderStats stats = render(scene, film, o);
    ASSERT_TRUE(stats.stopped_after_pass) << target;
    EXPECT_FALSE(stats.interrupted);
    EXPECT_TRUE(is_look(stats.samples_done, rule.min_spp)) << stats.samples_done;
    const Image img = film.to_image(stats.samples_done);
    const ImageLayer& x = img.layers[0];
    double se = 0, sum_r = 0, sum_d = 0, sum_d2 = 0;  // sum_d*: of each pixel's error summed over channels
    for (size_t p = 0; p < r.pixels.size() / 3; ++p) {
      double dp = 0;
      for (size_t i = 3 * p; i < 3 * p + 3; ++i) {
        const double d = double(x.pixels[i]) - r.pixels[i];
        se += d * d, sum_r += r.pixels[i], dp += d;
      }
      sum_d += dp, sum_d2 += dp * dp;
    }
    const double n = double(r.pixels.size()), pixels = n / 3;
    const double achieved = std::sqrt(se / n) / (sum_r / n);
    std::printf("target %.3f: stopped at %d spp, estimated %.4f, achieved %.4f\n", target, stats.samples_done, estimate, achieved);
    EXPECT_LE(estimate, target);
    EXPECT_LE(achieved, 1.25 * target);
    EXPECT_GE(achieved, 0.75 * target / std::sqrt(2.0));
    const double mean_d = sum_d / pixels, sigma = std::sqrt((sum_d2 / pixels - mean_d * mean_d) / (pixels - 1));
    EXPECT_NEAR(mean_d, 0.0, 4 * sigma);
  }
}
