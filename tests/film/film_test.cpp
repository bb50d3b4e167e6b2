#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/rng.h"
#include "film/film.h"
#include "spectra/color.h"
#include "spectra/library.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

namespace {

// Sample mean and standard error of a stream of values.
struct Stats {
  double sum = 0, sum2 = 0;
  int n = 0;
  void add(double v) { sum += v, sum2 += v * v, ++n; }
  double mean() const { return sum / n; }
  double sigma() const { return std::sqrt(std::max(0.0, sum2 / n - mean() * mean()) / (n - 1)); }
};

}  // namespace

TEST(Film, ConstantSpectrumGivesItsXyzAndRgb) {
  const Spectrum one = Spectrum::constant(1.f);
  const XYZ exact = spectrum_to_xyz(one);
  Film film(3, 2, {"beauty"}, ColorSpace::sRGB);
  Rng rng(test_seed(5), 0);
  const int spp = 4000;
  Stats x, y, z;
  for (int k = 0; k < spp; ++k) {
    const SampledWavelengths lambda = SampledWavelengths::sample_visible(rng.uniform(), 4);
    const SampledSpectrum L = one.sample(lambda);
    film.add_sample(1, 1, 0, L, lambda);
    const XYZ e = to_xyz(L, lambda);
    x.add(e.x), y.add(e.y), z.add(e.z);
  }
  const size_t p = (1 * 3 + 1) * 3;
  const std::vector<double>& raw = film.raw_xyz(0);
  EXPECT_NEAR(raw[p + 0] / spp, x.mean(), 1e-12);
  EXPECT_NEAR(raw[p + 1] / spp, y.mean(), 1e-12);
  EXPECT_NEAR(raw[p + 2] / spp, z.mean(), 1e-12);
  EXPECT_NEAR(y.mean(), exact.y, 4 * y.sigma());
  EXPECT_NEAR(x.mean(), exact.x, 4 * x.sigma());
  EXPECT_NEAR(z.mean(), exact.z, 4 * z.sigma());

  const Image img = film.to_image(spp);
  ASSERT_EQ(img.layers.size(), 2u);  // the mean, then its standard error
  EXPECT_EQ(img.layers[0].name, "beauty");
  EXPECT_EQ(img.layers[1].name, "beauty_stderr");
  EXPECT_EQ(img.layers[0].channels, (std::vector<std::string>{"R", "G", "B"}));
  const RGB expected = xyz_to_linear_srgb({x.mean(), y.mean(), z.mean()});
  const float* px = &img.layers[0].pixels[(1 * 3 + 1) * 3];
  EXPECT_NEAR(px[0], expected.r, 1e-6);
  EXPECT_NEAR(px[1], expected.g, 1e-6);
  EXPECT_NEAR(px[2], expected.b, 1e-6);
  // Equal energy is close to (but not exactly) the sRGB white.
  const RGB white = xyz_to_linear_srgb(exact);
  EXPECT_NEAR(px[0], white.r, 0.02);
  EXPECT_NEAR(px[1], white.g, 0.02);
  EXPECT_NEAR(px[2], white.b, 0.02);
  // Pixels without samples stay black.
  for (int c = 0; c < 3; ++c) EXPECT_EQ(img.layers[0].pixels[c], 0.f);
  EXPECT_EQ(std::get<double>(*img.metadata.find("samples_per_pixel")), spp);
}

TEST(Film, D65IsNeutralInAcesCg) {
  const Spectrum d65 = named_spectrum("D65").scaled(0.01f);
  Film film(1, 1, {"beauty"}, ColorSpace::ACEScg);
  Rng rng(test_seed(9), 0);
  const int spp = 20000;
  for (int k = 0; k < spp; ++k) {
    const SampledWavelengths lambda = SampledWavelengths::sample_visible(rng.uniform(), 8);
    film.add_sample(0, 0, 0, d65.sample(lambda), lambda);
  }
  const Image img = film.to_image(spp);
  const std::vector<float>& px = img.layers[0].pixels;
  EXPECT_NEAR(px[0] / px[1], 1.f, 0.01f);
  EXPECT_NEAR(px[2] / px[1], 1.f, 0.01f);
  EXPECT_FLOAT_EQ(float(img.chromaticities->white_x), 0.32168f);
}

TEST(Film, NonFiniteSamplesAreCountedAndDropped) {
  Film clean(2, 1, {"beauty", "fluorescence"}, ColorSpace::sRGB);
  Film dirty(2, 1, {"beauty", "fluorescence"}, ColorSpace::sRGB);
  const SampledWavelengths lambda = SampledWavelengths::sample_visible(0.3f, 4);
  const SampledSpectrum L = Spectrum::constant(2.f).sample(lambda);
  SampledSpectrum nan = L, inf = L;
  nan[2] = std::numeric_limits<float>::quiet_NaN();
  inf[0] = std::numeric_limits<float>::infinity();
  for (Film* f : {&clean, &dirty}) {
    f->add_sample(0, 0, 0, L, lambda);
    f->add_sample(1, 0, 1, L, lambda);
  }
  dirty.add_sample(0, 0, 0, nan, lambda);
  dirty.add_sample(1, 0, 1, inf, lambda);
  EXPECT_EQ(clean.nonfinite_samples(), 0u);
  EXPECT_EQ(dirty.nonfinite_samples(), 2u);
  const Image a = clean.to_image(1), b = dirty.to_image(1);
  for (size_t l = 0; l < a.layers.size(); ++l) {
    EXPECT_EQ(a.layers[l].pixels, b.layers[l].pixels);
    for (float v : b.layers[l].pixels) EXPECT_TRUE(std::isfinite(v));
  }
  EXPECT_EQ(std::get<double>(*b.metadata.find("nonfinite_samples")), 2.0);
}

TEST(Film, SpectralBinsRecoverATabulatedSpectrum) {
  const Spectrum d65 = named_spectrum("D65");
  const float lo = 400, hi = 700;
  const int bins = 15, count = 4, spp = 20000;
  Film film(1, 1, {"beauty"}, ColorSpace::sRGB);
  film.enable_spectral(lo, hi, bins);
  const double width = (hi - lo) / bins;
  std::vector<Stats> stats(bins);
  Rng rng(test_seed(21), 0);
  for (int k = 0; k < spp; ++k) {
    const SampledWavelengths lambda = SampledWavelengths::sample_visible(rng.uniform(), count);
    const SampledSpectrum L = d65.sample(lambda);
    film.add_sample(0, 0, 0, L, lambda);
    std::vector<double> sample(bins, 0.0);  // this sample's estimate of each bin average
    for (int i = 0; i < count; ++i)
      if (lambda[i] >= lo && lambda[i] < hi) sample[int((lambda[i] - lo) / width)] += L[i] / (lambda.pdf(i) * count * width);
    for (int b = 0; b < bins; ++b) stats[b].add(sample[b]);
  }
  const Image img = film.to_image(spp);
  const ImageLayer* s0 = img.find_layer("S0");
  ASSERT_NE(s0, nullptr);
  ASSERT_EQ(s0->channels.size(), size_t(bins));
  EXPECT_EQ(s0->channels[0], "410,0nm");
  EXPECT_EQ(s0->channels[14], "690,0nm");
  for (int b = 0; b < bins; ++b) {
    const double exact = d65.integral(lo + b * width, lo + (b + 1) * width) / width;
    EXPECT_NEAR(s0->pixels[b], stats[b].mean(), 1e-5 * stats[b].mean()) << b;
    EXPECT_NEAR(s0->pixels[b], exact, 4 * stats[b].sigma()) << "bin " << b << " sigma " << stats[b].sigma();
  }
}

TEST(Film, MergeAddsSums) {
  const Spectrum d65 = named_spectrum("D65");
  Film all(2, 2, {"beauty"}, ColorSpace::sRGB), first(2, 2, {"beauty"}, ColorSpace::sRGB), second(2, 2, {"beauty"}, ColorSpace::sRGB);
  for (Film* f : {&all, &first, &second}) f->enable_spectral(360, 830, 47);
  Rng rng(test_seed(2), 0);
  for (int k = 0; k < 200; ++k) {
    const SampledWavelengths lambda = SampledWavelengths::sample_visible(rng.uniform(), 4);
    const SampledSpectrum L = d65.sample(lambda);
    all.add_sample(k % 2, 1, 0, L, lambda);
    (k < 100 ? first : second).add_sample(k % 2, 1, 0, L, lambda);
  }
  first.merge(second);
  for (size_t i = 0; i < all.raw_xyz(0).size(); ++i) EXPECT_NEAR(first.raw_xyz(0)[i], all.raw_xyz(0)[i], 1e-9 * std::fabs(all.raw_xyz(0)[i]));
  for (size_t i = 0; i < all.raw_spectral().size(); ++i)
    EXPECT_NEAR(first.raw_spectral()[i], all.raw_spectral()[i], 1e-9 * std::fabs(all.raw_spectral()[i]));
  Film other(2, 2, {"beauty", "fluorescence"}, ColorSpace::sRGB);
  EXPECT_THROW(first.merge(other), std::invalid_argument);
  // A moved film keeps its sums.
  const Film moved = std::move(first);
  EXPECT_NEAR(moved.raw_xyz(0)[(1 * 2 + 1) * 3 + 1], all.raw_xyz(0)[(1 * 2 + 1) * 3 + 1], 1e-9);
}

// The standard-error layer is that of the mean of the camera samples, each
// sample's hero wavelengths summed first (one sample = one i.i.d. draw).
TEST(Film, StandardErrorLayerIsTheErrorOfTheMeanOfCameraSamples) {
  const Spectrum d65 = named_spectrum("D65").scaled(0.01f);
  Film film(2, 1, {"beauty"}, ColorSpace::sRGB);
  Rng rng(test_seed(31), 0);
  const int spp = 500;
  Stats r, g, b;
  for (int k = 0; k < spp; ++k) {
    const SampledWavelengths lambda = SampledWavelengths::sample_visible(rng.uniform(), 4);
    const SampledSpectrum L = d65.sample(lambda);
    film.add_sample(1, 0, 0, L, lambda);
    const RGB e = xyz_to_linear_srgb(to_xyz(L, lambda));
    r.add(e.r), g.add(e.g), b.add(e.b);
  }
  const Image img = film.to_image(spp);
  const ImageLayer* se = img.find_layer("beauty_stderr");
  ASSERT_NE(se, nullptr);
  EXPECT_EQ(se->channels, (std::vector<std::string>{"R", "G", "B"}));
  EXPECT_NEAR(se->pixels[3], r.sigma(), 1e-5 * r.sigma());
  EXPECT_NEAR(se->pixels[4], g.sigma(), 1e-5 * g.sigma());
  EXPECT_NEAR(se->pixels[5], b.sigma(), 1e-5 * b.sigma());
  EXPECT_GT(se->pixels[4], 0.f);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(se->pixels[c], 0.f);  // no samples
  // Merging two halves gives the same moments as one film.
  Film half_a(2, 1, {"beauty"}, ColorSpace::sRGB), half_b(2, 1, {"beauty"}, ColorSpace::sRGB);
  Rng again(test_seed(31), 0);
  for (int k = 0; k < spp; ++k) {
    const SampledWavelengths lambda = SampledWavelengths::sample_visible(again.uniform(), 4);
    (k < 200 ? half_a : half_b).add_sample(1, 0, 0, d65.sample(lambda), lambda);
  }
  half_a.merge(half_b);
  for (size_t i = 0; i < 6; ++i)
    EXPECT_NEAR(half_a.raw_rgb_squares(0)[i], film.raw_rgb_squares(0)[i], 1e-12 * (1 + film.raw_rgb_squares(0)[i]));
}

TEST(Film, StandardErrorHelpersInvertEachOther) {
  EXPECT_EQ(stderr_layer_name("total"), "total_stderr");
  EXPECT_TRUE(is_stderr_layer("total_stderr"));
  EXPECT_FALSE(is_stderr_layer("total"));
  EXPECT_FALSE(is_stderr_layer("_stderr"));
  EXPECT_EQ(stderr_base_name("fluorescence_stderr"), "fluorescence");
  const double mean = 2.5, se = 0.125, n = 40;
  EXPECT_NEAR(standard_error(mean, sum_of_squares(mean, se, n), n), se, 1e-12);
  EXPECT_EQ(standard_error(mean, 1.0, 1), 0.0);
}

TEST(Film, AovLayersAreMeansOverTheSamplesAndMergeLikeSums) {
  Film a(2, 1, {"total"}, ColorSpace::sRGB);
  a.enable_aovs(kAovAlpha | kAovDepth | kAovNormal);
  const SampledWavelengths lambda = SampledWavelengths::sample_visible(0.3f, 4);
  const SampledSpectrum black(0.f);
  AovSample hit;
  hit.surface = true;
  hit.depth = 2.f;
  hit.normal = {0, 0, 1};
  AovSample miss;  // vacuum behind: transmittance 1
  Film b = a.empty_like();
  EXPECT_EQ(b.aovs(), a.aovs());
  a.add_sample(0, 0, {&black, 1}, lambda, &hit);
  a.add_sample(0, 0, {&black, 1}, lambda, &miss);
  hit.depth = 4.f;
  b.add_sample(0, 0, {&black, 1}, lambda, &hit);
  b.add_sample(0, 0, {&black, 1}, lambda, &hit);
  a.merge(b);  // pixel 0: 4 samples, 3 hits at depths 2, 4, 4; pixel 1: nothing
  const Image img = a.to_image(4);
  const ImageLayer* alpha = img.find_layer("alpha");
  const ImageLayer* depth = img.find_layer("depth");
  const ImageLayer* normal = img.find_layer("N");
  ASSERT_TRUE(alpha && depth && normal);
  EXPECT_EQ(img.find_layer("albedo"), nullptr) << "only the layers asked for";
  EXPECT_DOUBLE_EQ(alpha->pixels[0], 0.75);
  EXPECT_FLOAT_EQ(depth->pixels[0], 10.f / 3.f);  // Z: over the samples that hit
  EXPECT_FLOAT_EQ(depth->pixels[1], 0.75f);       // coverage
  EXPECT_TRUE(std::isinf(depth->pixels[2]));       // pixel 1 saw no surface
  EXPECT_FLOAT_EQ(normal->pixels[2], 0.75f);
  EXPECT_EQ(std::get<std::string>(*img.metadata.find("aovs")), "alpha,depth,normal");
  Film other(2, 1, {"total"}, ColorSpace::sRGB);
  EXPECT_THROW(a.merge(other), std::invalid_argument);
  std::string unknown;
  EXPECT_EQ(aov_mask({"albedo", "alpha"}, &unknown), AovMask(kAovAlbedo | kAovAlpha));
  EXPECT_EQ(aov_mask({"albedo", "colour"}, &unknown), 0u);
  EXPECT_EQ(unknown, "colour");
}
