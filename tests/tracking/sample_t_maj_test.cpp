#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/sampling.h"
#include "slab_fixture.h"
#include "tracking/sample_t_maj.h"
#include "test_seed.h"

using namespace chlorovdb;
using namespace chlorovdb::test;

namespace {

// Kolmogorov-Smirnov distance between sampled first-collision distances
// (censored at `length` when there was none) and the CDF 1 - exp(-tau(t)).
double ks_distance(std::vector<double> t, double length, const std::function<double(double)>& tau) {
  std::sort(t.begin(), t.end());
  const double n = double(t.size());
  double d = 0;
  for (size_t i = 0; i < t.size() && t[i] < length; ++i) {
    const double F = 1.0 - std::exp(-tau(t[i]));
    d = std::max({d, std::fabs(double(i) / n - F), std::fabs(double(i + 1) / n - F)});
  }
  // The censored mass: P(no collision) = exp(-tau(length)).
  const size_t censored = size_t(std::count_if(t.begin(), t.end(), [&](double x) { return x >= length; }));
  d = std::max(d, std::fabs(double(censored) / n - std::exp(-tau(length))));
  return d;
}

// First real collision along the slab's ray, with real/null decided on the hero lane.
std::vector<double> first_real_collisions(const Slab& s, int n, uint64_t seed) {
  const SampledWavelengths lambda = four_wavelengths();
  const PreparedMedium pm = prepare(*s.medium, lambda);
  Rng rng(test_seed(seed), 0);
  std::vector<double> out;
  for (int i = 0; i < n; ++i) {
    double hit = 1e30;
    sample_T_maj(s.ray, s.t_max, rng.uniform(), rng, lambda, *s.medium, pm,
                 [&](const Vec3& p, const MediumCollision& c, const SampledSpectrum& sigma_maj, const MajorantTransmittance&) {
                   if (rng.uniform() * sigma_maj[0] >= c.sigma_t()[0]) return true;  // null
                   hit = double(length(p - s.ray.o));
                   return false;
                 });
    out.push_back(hit);
  }
  return out;
}

constexpr double kKsCritical = 1.95;  // sqrt(N) * D at alpha = 0.001

}  // namespace

TEST(SampleTMaj, FreeFlightIsExponentialInAHomogeneousMedium) {
  const Slab s = homogeneous_slab(1.5);
  const int n = 20000;
  const double length = double(chlorovdb::length(s.ray.d)) * s.t_max;
  const double d = ks_distance(first_real_collisions(s, n, 1), length, [&](double t) { return s.tau_to(t, 0); });
  EXPECT_LT(d * std::sqrt(double(n)), kKsCritical);
}

TEST(SampleTMaj, FirstRealCollisionFollowsTheOpticalDepthInAGrid) {
  const Slab s = piecewise_linear_slab(2.0, rough_profile());
  const int n = 20000;
  const double length = double(chlorovdb::length(s.ray.d)) * s.t_max;
  const double d = ks_distance(first_real_collisions(s, n, 2), length, [&](double t) { return s.tau_to(t, 0); });
  EXPECT_LT(d * std::sqrt(double(n)), kKsCritical);
}

TEST(SampleTMaj, MajorantTransmittanceChainsAcrossSegments) {
  // Always null: the product of the T_maj handed out and the one returned is
  // exp(-integral of sigma_maj) over the whole ray, per lane, whatever the segments.
  const Slab s = piecewise_linear_slab(6.0, rough_profile());
  const SampledWavelengths lambda = four_wavelengths();
  const PreparedMedium pm = prepare(*s.medium, lambda);
  const float len = chlorovdb::length(s.ray.d);
  const Ray ri = s.medium->index_ray({s.ray.o, s.ray.d / len});
  SampledSpectrum expected_log;
  auto it = s.medium->majorants(ri, s.t_max * len);
  while (auto seg = it.next()) expected_log += pm.sigma_maj(*seg, s.medium->channels()) * (seg->t_max - seg->t_min);
  Rng rng(test_seed(3), 0);
  SampledSpectrum product(1.f);
  int collisions = 0;
  const SampledSpectrum last = sample_T_maj(s.ray, s.t_max, rng.uniform(), rng, lambda, *s.medium, pm,
                                            [&](const Vec3&, const MediumCollision&, const SampledSpectrum&,
                                                const MajorantTransmittance& T_maj) {
                                              product *= T_maj();
                                              ++collisions;
                                              return true;
                                            });
  product *= last;
  EXPECT_GT(collisions, 3);
  for (int l = 0; l < 4; ++l) EXPECT_NEAR(std::log(product[l]), -expected_log[l], 1e-3f * expected_log[l]);
  EXPECT_EQ(last[4], 0.f);
}

TEST(SampleTMaj, GreyMediaKeepOneLaneAndBroadcastIt) {
  // Always null in a grey medium: T_maj() holds one value on every carried lane, and
  // the chain multiplies to exp(-integral of sigma_maj).
  const Slab s = piecewise_linear_slab(6.0, rough_profile());
  double tau = 0;
  const std::shared_ptr<Medium> grey = grey_medium_on(s, &tau);
  const SampledWavelengths lambda = four_wavelengths();
  const PreparedMedium pm = prepare(*grey, lambda);
  ASSERT_TRUE(pm.grey);
  const float len = chlorovdb::length(s.ray.d);
  const Ray ri = grey->index_ray({s.ray.o, s.ray.d / len});
  double expected_log = 0;
  auto it = grey->majorants(ri, s.t_max * len);
  while (auto seg = it.next()) expected_log += pm.sigma_maj(*seg, grey->channels())[0] * (seg->t_max - seg->t_min);
  Rng rng(test_seed(5), 0);
  double log_product = 0;
  int collisions = 0;
  const SampledSpectrum last = sample_T_maj(
      s.ray, s.t_max, rng.uniform(), rng, lambda, *grey, pm,
      [&](const Vec3&, const MediumCollision&, const SampledSpectrum& sigma_maj, const MajorantTransmittance& T_maj) {
        const SampledSpectrum T = T_maj();
        for (int l = 1; l < 4; ++l) {
          EXPECT_EQ(T[l], T[0]);
          EXPECT_EQ(sigma_maj[l], sigma_maj[0]);
        }
        EXPECT_EQ(T[4], 0.f);
        log_product += std::log(double(T[0]));
        ++collisions;
        return true;
      });
  for (int l = 1; l < 4; ++l) EXPECT_EQ(last[l], last[0]);
  EXPECT_EQ(last[4], 0.f);
  log_product += std::log(double(last[0]));
  EXPECT_GT(collisions, 3);
  EXPECT_NEAR(log_product, -expected_log, 1e-3 * expected_log);
}

TEST(SampleTMaj, NoCoefficientExceedsItsMajorantInSpikyGrids) {
  // Two pigments on grids with different transforms, plus a particle grid, all with random spikes.
  auto spiky = [](Coord dims, uint64_t seed, const Transform& world_from_index) {
    DenseGrid d(dims);
    Rng rng(test_seed(seed), 0);
    for (float& v : d.values) v = rng.uniform() < 0.02f ? 50.f * rng.uniform() : (rng.uniform() < 0.5f ? 0.f : rng.uniform());
    d.world_from_index = world_from_index;
    return std::make_shared<const VoxelGrid>(VoxelGrid::from_dense(d));
  };
  const auto g0 = spiky({40, 30, 35}, 1, Transform::scale({0.01f, 0.012f, 0.009f}));
  const auto g1 = spiky({25, 25, 25}, 2, Transform::translate({0.05f, 0.02f, 0.f}) * Transform::rotate(40.f, {1, 0, 1}) *
                                            Transform::scale({0.013f, 0.011f, 0.017f}));
  const auto g2 = spiky({20, 20, 20}, 3, Transform::scale({0.02f, 0.02f, 0.02f}));
  for (Interpolation mode : {Interpolation::trilinear, Interpolation::nearest}) {
    MediumDesc d = water_desc();
    d.pigments.push_back({ramp_pigment(), Field::from_grid(g0, 1e-6f)});
    d.pigments.push_back({ramp_pigment(), Field::from_grid(g1, 2e-6f)});
    d.particle_sigma_s = Field::from_grid(g2, 10.f);
    d.interpolation = mode;
    const Medium m(d);
    ASSERT_EQ(m.channels(), 3);
    const SampledWavelengths lambda = four_wavelengths();
    const PreparedMedium pm = prepare(m, lambda);
    Rng rng(test_seed(4), 0);
    int64_t checked = 0;
    for (int r = 0; r < 4000; ++r) {
      const Vec3 o{-0.1f + 0.6f * rng.uniform(), -0.1f + 0.6f * rng.uniform(), -0.1f + 0.6f * rng.uniform()};
      const Ray ray{o, sample_uniform_sphere({rng.uniform(), rng.uniform()})};
      sample_T_maj(ray, 0.8f, rng.uniform(), rng, lambda, m, pm,
                   [&](const Vec3&, const MediumCollision& c, const SampledSpectrum& sigma_maj, const MajorantTransmittance&) {
                     const MediumProperties mp = c.properties();
                     const SampledSpectrum sigma_t = c.sigma_t();
                     for (int l = 0; l < 4; ++l) {
                       EXPECT_LE(mp.sigma_a[l] + mp.sigma_s[l], sigma_maj[l] * (1.f + 1e-5f));
                       EXPECT_LE(sigma_t[l], sigma_maj[l] * (1.f + 1e-5f));
                       EXPECT_NEAR(c.sigma_s(l), mp.sigma_s[l], 1e-6f * mp.sigma_s[l]);
                       ++checked;
                     }
                     return true;
                   });
      // And at many points per segment, not only where collisions fell.
      const Ray ri = m.index_ray(ray);
      auto it = m.majorants(ri, 0.8f);
      while (auto seg = it.next()) {
        const SampledSpectrum hi = pm.sigma_maj(*seg, m.channels());
        for (int k = 0; k < 16; ++k) {
          const SampledSpectrum st = m.sigma_t(ri.at(seg->t_min + rng.uniform() * (seg->t_max - seg->t_min)), pm);
          for (int l = 0; l < 4; ++l) ASSERT_LE(st[l], hi[l] * (1.f + 1e-5f));
          ++checked;
        }
      }
    }
    EXPECT_GT(checked, 500000);
  }
}

TEST(SampleTMaj, EmptySpaceCostsNoLookups) {
  // Two small blobs 200 voxels apart, no solvent: collisions (each one a
  // lookup) happen only inside the blobs' cells, and the empty stretch between
  // them comes out of the DDA as a single segment.
  DenseGrid g({256, 16, 16});
  for (int x0 : {10, 240})
    for (int z = 6; z < 10; ++z)
      for (int y = 6; y < 10; ++y)
        for (int x = x0; x < x0 + 4; ++x) g.at(x, y, z) = 1.f;
  g.world_from_index = Transform::scale({0.001f, 0.001f, 0.001f});
  MediumDesc d;
  d.pigments.push_back({ramp_pigment(), Field::from_grid(std::make_shared<const VoxelGrid>(VoxelGrid::from_dense(g)), 1e-5f)});
  const Medium m(d);
  const SampledWavelengths lambda = four_wavelengths();
  const PreparedMedium pm = prepare(m, lambda);
  const Ray ray{{-0.01f, 0.0075f, 0.0075f}, {1.f, 0.f, 0.f}};
  int segments = 0, nonempty = 0;
  auto it = m.majorants(m.index_ray(ray), 0.3f);
  while (auto s = it.next()) {
    ++segments;
    nonempty += s->c_max[0] > 0.f;
  }
  EXPECT_EQ(segments - nonempty, 3);  // before, between and after the blobs
  EXPECT_LE(nonempty, 4);             // a 4-voxel blob (+ stencil) spans at most 2 cells of 8
  Rng rng(test_seed(5), 0);
  int lookups = 0, in_empty = 0;
  for (int i = 0; i < 2000; ++i)
    sample_T_maj(ray, 0.3f, rng.uniform(), rng, lambda, m, pm,
                 [&](const Vec3& p, const MediumCollision&, const SampledSpectrum&, const MajorantTransmittance&) {
                   ++lookups;
                   const float x = p.x / 0.001f;
                   in_empty += x > 30.f && x < 225.f;
                   return true;
                 });
  EXPECT_GT(lookups, 1000);
  EXPECT_EQ(in_empty, 0);
}

TEST(SampleTMaj, FurnaceWithAChromaticPureScattererReturnsOnePerLane) {
  // Rayleigh scattering (lambda^-4) plus a particle grid, nothing absorbs, in a
  // 1.3 km box lit by a uniform environment of radiance 1: every lane must see 1.
  // Distances come from the hero lane; the other lanes carry the ratios
  // T_maj sigma / (T_maj[0] sigma[0]) that keep them unbiased. The hero is the
  // most scattering lane (450 nm): a lane that scatters more than the hero has
  // longer paths than the hero samples, and its ratios then have no usable
  // variance (with a 650 nm hero, the 450 nm lane's standard deviation per path
  // came out 34 on one seed and 201 on another at 2e6 paths, and the 4-sigma
  // check failed on 2 of 12 seeds). The renderer's spectral MIS (r_u) is what
  // bounds that case.
  DenseGrid g({64, 64, 64});
  Rng grid_rng(6, 0);
  for (float& v : g.values) v = grid_rng.uniform() < 0.3f ? 0.f : grid_rng.uniform();
  g.world_from_index = Transform::translate({10.f, 10.f, 10.f}) * Transform::scale({20.f, 20.f, 20.f});
  const auto grid = std::make_shared<const VoxelGrid>(VoxelGrid::from_dense(g));
  MediumDesc d;
  d.solvent = Solvent::water(Spectrum::constant(0.f), Spectrum::constant(1.337f));
  d.particle_sigma_s = Field::from_grid(grid, 3e-3f);
  d.particle_phase = HenyeyGreenstein{0.5f};
  const Medium m(d);
  const Bounds3 box = grid->world_bounds(d.interpolation);
  const float lambda_nm[] = {450.f, 650.f, 550.f, 700.f}, lambda_pdf[] = {1.f, 1.f, 1.f, 1.f};
  const SampledWavelengths lambda = SampledWavelengths::from_values(lambda_nm, lambda_pdf, 4);
  const PreparedMedium pm = prepare(m, lambda);
  Rng rng(test_seed(7), 0);
  const int n = 20000;
  double sum[4] = {}, sum2[4] = {};
  for (int i = 0; i < n; ++i) {
    SampledSpectrum beta(1.f);
    Ray ray{box.center(), sample_uniform_sphere({rng.uniform(), rng.uniform()})};
    for (int bounce = 0; bounce < 10000; ++bounce) {
      float t0, t1;
      ASSERT_TRUE(intersect_bounds(box, ray, kInfinity, &t0, &t1));  // every path starts inside
      bool scattered = false;
      const SampledSpectrum T_maj = sample_T_maj(
          ray, t1, rng.uniform(), rng, lambda, m, pm,
          [&](const Vec3& p, const MediumCollision& c, const SampledSpectrum& sigma_maj,
              const MajorantTransmittance& T_m) {
            const MediumProperties mp = c.properties();
            const SampledSpectrum T = T_m();
            if (rng.uniform() * sigma_maj[0] < mp.sigma_s[0]) {
              beta *= T * mp.sigma_s / (T[0] * mp.sigma_s[0]);
              const MediumPhaseSample ps = phase_sample(mp.phase, -ray.d, {rng.uniform(), rng.uniform()});
              beta *= ps.p / ps.pdf;
              ray = Ray{p, ps.wi};
              scattered = true;
              return false;
            }
            const SampledSpectrum sigma_n = sigma_maj - mp.sigma_s;
            beta *= T * sigma_n / (T[0] * sigma_n[0]);
            return true;
          });
      if (scattered) continue;
      beta *= T_maj / T_maj[0];
      break;
    }
    for (int l = 0; l < 4; ++l) {
      sum[l] += beta[l];
      sum2[l] += double(beta[l]) * beta[l];
    }
  }
  for (int l = 0; l < 4; ++l) {
    const double mean = sum[l] / n, se = std::sqrt(std::max(0.0, sum2[l] / n - mean * mean) / n);
    if (l == 0) {
      EXPECT_NEAR(mean, 1.0, 1e-5);  // the hero's weight is exactly 1 on every path
    } else {
      EXPECT_NEAR(mean, 1.0, 4.0 * se) << "lane " << l;
      EXPECT_GT(se, 1e-4) << "lane " << l << " was not reweighted at all";
    }
  }
}
