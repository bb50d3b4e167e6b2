// The renderer's side of adaptive sampling (film/adaptive.h, RenderOptions::pixel_spp):
// a pixel given n samples holds exactly the samples a uniform render of n spp
// gives it (so it is as unbiased as that render), and the pilot-driven image of
// the analytic slab matches its exact value.
#include "scratch_dir.h"
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "analysis/analytic_slab.h"
#include "film/adaptive.h"
#include "integrator/render.h"
#include "scene/scene_loader.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

namespace {

Scene slab_scene(SlabCase& slab) {
  slab = analytic_case("slab");
  slab.name = "adaptive_render";
  slab.resolution = 8;
  return load_scene(write_slab_scene(slab, chlorovdb::test::scratch_dir("analysis_tests")));
}

Film make_film(const Scene& scene) {
  return Film(scene.settings.width, scene.settings.height, film_layer_names(), scene.settings.color_space);
}

}  // namespace

TEST(AdaptiveRender, PixelsHoldExactlyTheirUniformRendersSamples) {
  SlabCase slab;
  const Scene scene = slab_scene(slab);
  Film film = make_film(scene);
  film.enable_sample_counts();
  std::vector<int> counts(size_t(film.width()) * size_t(film.height()));
  for (size_t p = 0; p < counts.size(); ++p) counts[p] = 1 + int(p % 13);  // 1 .. 13: partial last passes
  RenderOptions o;
  o.seed = test_seed(1300);
  o.first_sample = 5;
  o.spp = 13;
  o.pixel_spp = &counts;
  const RenderStats stats = render(scene, film, o);
  EXPECT_EQ(stats.samples_done, 13);
  EXPECT_EQ(film.raw_sample_counts(), std::vector<double>(counts.begin(), counts.end()));
  for (const int n : {1, 4, 7, 13}) {
    Film uniform = make_film(scene);
    RenderOptions u = o;
    u.pixel_spp = nullptr;
    u.spp = n;
    render(scene, uniform, u);
    for (size_t p = 0; p < counts.size(); ++p)
      if (counts[p] == n)
        for (int i = 0; i < 3; ++i) {
          EXPECT_EQ(film.raw_xyz(0)[3 * p + i], uniform.raw_xyz(0)[3 * p + i]) << p;
          EXPECT_EQ(film.raw_rgb_squares(0)[3 * p + i], uniform.raw_rgb_squares(0)[3 * p + i]) << p;
        }
  }
  Film uncounted = make_film(scene);
  EXPECT_THROW(render(scene, uncounted, o), std::invalid_argument);
}

// Pilot (its own seed) -> counts -> image, as the render session runs it; the
// image's mean over pixels matches the exact slab within 4 standard errors (from
// the pixels' spread: every pixel is a replicate of the same exact value).
TEST(AdaptiveRender, SlabImageMatchesTheExactValue) {
  SlabCase slab;
  const Scene scene = slab_scene(slab);
  const Image truth = slab_reference_image(slab, scene);
  AdaptiveSampling a;
  a.target_relative_error = 0.1;
  Film pilot = make_film(scene);
  RenderOptions po;
  po.seed = pilot_seed(test_seed(1310));
  po.spp = a.pilot_spp;
  render(scene, pilot, po);
  const std::vector<int> counts = adaptive_sample_counts(pilot, a);
  Film film = make_film(scene);
  film.enable_sample_counts();
  RenderOptions o;
  o.seed = test_seed(1310);
  o.spp = *std::max_element(counts.begin(), counts.end());
  o.pixel_spp = &counts;
  render(scene, film, o);
  const Image img = film.to_image(1);
  const ImageLayer& x = img.layers[0];
  const ImageLayer& r = truth.layers[0];
  const size_t pixels = r.pixels.size() / 3;
  double sum_d = 0, sum_d2 = 0;
  for (size_t p = 0; p < pixels; ++p) {
    double d = 0;
    for (size_t i = 3 * p; i < 3 * p + 3; ++i) d += double(x.pixels[i]) - r.pixels[i];
    sum_d += d, sum_d2 += d * d;
  }
  const double mean_d = sum_d / pixels, sigma = std::sqrt((sum_d2 / pixels - mean_d * mean_d) / (pixels - 1));
  EXPECT_NEAR(mean_d, 0.0, 4 * sigma);
  EXPECT_GT(*std::min_element(counts.begin(), counts.end()), a.min_spp - 1);
}
