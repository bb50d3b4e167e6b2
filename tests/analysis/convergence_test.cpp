// CI-sized convergence checks, one per estimator, on the analytic slabs
// (analysis/analytic_slab.h, docs/physics.md §7): RMSE against samples falls with a
// log-log slope of -1/2 +- 0.1 and the mean shows no bias at 4 sigma.
// Each pixel of the 16x16 image is an independent replicate of the same exact
// value, so one progressive render gives both the RMSE and its standard error.
#include "scratch_dir.h"
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "analysis/analytic_slab.h"
#include "analysis/loglog_fit.h"
#include "analysis/progressive.h"
#include "lights/light.h"
#include "scene/scene_loader.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

namespace {

struct Outcome {
  double slope = 0;
  std::vector<double> bias_in_sigmas;  // per channel of the total layer at the largest sample count
};

Outcome converge(SlabCase slab, const std::string& tag) {
  slab.name += "_" + tag;
  const auto dir = chlorovdb::test::scratch_dir("analysis_tests");
  const Scene scene = load_scene(write_slab_scene(slab, dir));
  const Image truth = slab_reference_image(slab, scene);
  ConvergenceOptions o;
  o.spp = {8, 32, 128, 512};
  o.seed = test_seed(1234);
  o.keep_images = true;
  const auto points = run_convergence(scene, truth, o);
  EXPECT_EQ(points.size(), 4u);
  std::vector<double> n, rmse;
  for (const ConvergencePoint& p : points) {
    n.push_back(p.spp);
    rmse.push_back(find_error(p.errors, "total")->rmse);
    // Only fluorescence reaches the camera.
    EXPECT_EQ(find_error(p.errors, "nonfluorescence")->mse, 0.0) << tag;
  }
  // The excitation routes accumulate over the progressive render's chunks.
  EXPECT_GT(points.back().excitation_routes.events_any, points.front().excitation_routes.events_any) << tag;
  EXPECT_GT(points.back().excitation_routes.sum[size_t(ExcitationRoute::connection)], 0.0) << tag;
  Outcome out;
  out.slope = fit_power_law(n, rmse).exponent;
  const ImageLayer& x = points.back().image.layers[0];
  const ImageLayer& r = truth.layers[0];
  const size_t pixels = size_t(truth.width) * truth.height;
  for (int c = 0; c < 3; ++c) {
    double sum = 0, sum2 = 0;
    for (size_t i = 0; i < pixels; ++i) {
      const double d = double(x.pixels[3 * i + c]) - r.pixels[3 * i + c];
      sum += d;
      sum2 += d * d;
    }
    const double mean = sum / pixels, sigma = std::sqrt(std::max(0.0, sum2 / pixels - mean * mean) / (pixels - 1));
    out.bias_in_sigmas.push_back(mean / sigma);
  }
  std::printf("%-28s slope %.3f  bias/sigma (R,G,B) %+.2f %+.2f %+.2f\n", tag.c_str(), out.slope, out.bias_in_sigmas[0],
              out.bias_in_sigmas[1], out.bias_in_sigmas[2]);
  return out;
}

void expect_converges(const SlabCase& slab, const std::string& tag) {
  const Outcome o = converge(slab, tag);
  EXPECT_NEAR(o.slope, -0.5, 0.1) << tag;
  for (double b : o.bias_in_sigmas) EXPECT_LT(std::abs(b), 4.0) << tag << ": biased";
}

SlabCase linear(const std::string& transmittance) {
  SlabCase s = analytic_case("slab_linear");
  s.transmittance = transmittance;
  return s;
}

}  // namespace

// Transmittance estimators, in the grid slab where the majorant is loose.
TEST(Convergence, RatioTrackingOnLinearSlab) { expect_converges(linear("ratio"), "ratio"); }
TEST(Convergence, ResidualRatioTrackingOnLinearSlab) { expect_converges(linear("residual_ratio"), "residual_ratio"); }
TEST(Convergence, DeltaTrackingOnLinearSlab) { expect_converges(linear("delta"), "delta"); }

// The fluorescence estimator: direct (closed-form transmittance in the
// homogeneous slab) on both faces, and full (excitation continuations).
TEST(Convergence, DirectFluorescenceOnSlab) { expect_converges(analytic_case("slab"), "direct"); }
TEST(Convergence, DirectFluorescenceOnSlabTransmissionSide) {
  expect_converges(analytic_case("slab_transmission"), "direct_transmission");
}
TEST(Convergence, FullFluorescenceOnSlab) {
  SlabCase s = analytic_case("slab");
  s.fluorescence = "full";
  expect_converges(s, "full");
}

TEST(AnalyticSlab, QuadratureMatchesTheClosedFormForAUniformSlab) {
  // The depth quadrature (used for graded slabs) must reproduce docs/physics.md §7's closed form:
  // L = Q f(l) / (4 pi l) * int l' E(l') dl' * mu_a (1 - e^{-(zeta + zeta + mu_a) D}) / (zeta + zeta + mu_a).
  const SlabCase slab = analytic_case("slab");
  const auto dir = chlorovdb::test::scratch_dir("analysis_tests");
  const Scene scene = load_scene(write_slab_scene(slab, dir));
  const double mu_a = 100 * std::log(10.0) * slab.epsilon * slab.c_lit * 1e-6;
  const Pigment& p = scene.media[0].desc().pigments[0].pigment;
  const Spectrum& E = emission_spectrum(scene.lights[0]);
  const int n = 100000;
  const double h = (slab.eps_hi - slab.eps_lo) / n;
  double lE = 0;
  for (int i = 0; i <= n; ++i) {
    const double l = slab.eps_lo + i * h;
    lE += (i == 0 || i == n ? 0.5 : 1.0) * h * l * E(float(l));
  }
  const double s = 2 * slab.zeta + mu_a;
  for (double lambda : {640.0, 650.0, 665.0}) {
    const double closed = p.quantum_yield * p.emission(float(lambda)) / (4 * M_PI * lambda) * lE * mu_a * -std::expm1(-s * slab.D) / s;
    EXPECT_NEAR(slab_radiance(slab, scene, lambda) / closed, 1.0, 1e-4) << lambda;
  }
}
