// `chlorovdb measure` (analysis/measure.h): on the analytic slab the confidence
// intervals cover the exact band-averaged spectral radiance and XYZ.
#include "scratch_dir.h"
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "analysis/analytic_slab.h"
#include "analysis/measure.h"
#include "scene/scene_loader.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

TEST(Measure, StudentQuantileMatchesTables) {
  EXPECT_NEAR(student_t_quantile(0.95, 15), 2.131, 0.002);
  EXPECT_NEAR(student_t_quantile(0.99, 9), 3.250, 0.01);
  EXPECT_NEAR(student_t_quantile(0.95, 1000), 1.962, 0.002);
}

// Each interval is at confidence 0.99994 (4 sigma two-sided): over the ~60 values
// checked, a correct estimator fails about once in 270 seeds.
TEST(Measure, IntervalsCoverTheExactSlabRadiance) {
  SlabCase slab = analytic_case("slab");
  slab.name = "measure";
  const Scene scene = load_scene(write_slab_scene(slab, chlorovdb::test::scratch_dir("analysis_tests")));
  MeasureOptions o;
  o.spp = 256;
  o.batches = 16;
  o.confidence = 0.99994;
  o.seed = test_seed(4242);
  const RegionMeasurement m = measure_region(scene, PixelWindow{4, 4, 10, 8}, o);
  ASSERT_EQ(m.layers.size(), 3u);
  const XYZ exact = slab_xyz(slab, scene);
  const double e[3] = {exact.x, exact.y, exact.z};
  for (int c = 0; c < 3; ++c) {
    for (int l : {0, 1}) {  // total = fluorescence
      EXPECT_NEAR(m.xyz[size_t(l)][size_t(c)].mean, e[c], m.xyz[size_t(l)][size_t(c)].half_width) << l << " " << c;
      EXPECT_GT(m.xyz[size_t(l)][size_t(c)].half_width, 0.0);
    }
    EXPECT_EQ(m.xyz[2][size_t(c)].mean, 0.0);  // nothing but fluorescence reaches the camera
  }
  // Band averages by Simpson's rule (20 intervals per 10 nm band; the emission is a 10 nm-wide Gaussian).
  std::vector<double> bands;
  for (size_t b = 0; b < m.spectral.size(); ++b) {
    const double lo = m.band_centre_nm[b] - m.band_width_nm / 2, h = m.band_width_nm / 20;
    double sum = 0;
    for (int i = 0; i <= 20; ++i) sum += (i == 0 || i == 20 ? 1 : i % 2 ? 4 : 2) * slab_radiance(slab, scene, lo + i * h);
    bands.push_back(sum * h / 3 / m.band_width_nm);
  }
  const double peak = *std::max_element(bands.begin(), bands.end());
  int checked = 0;
  for (size_t b = 0; b < m.spectral.size(); ++b) {
    const double band = bands[b];
    if (band < 1e-3 * peak) continue;  // the Gaussian's far tails: too few samples land there for an interval
    EXPECT_NEAR(m.spectral[b].mean, band, m.spectral[b].half_width) << m.band_centre_nm[b] << " nm";
    ++checked;
  }
  EXPECT_GE(checked, 5);
  EXPECT_GT(m.radiance.mean, 0.0);
}
