// sample_emission: what the photons of render.excitation_estimate = photons leave the lights with.
#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "lights/light_emission.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

namespace {

struct FluxEstimate {
  double mean = 0, sigma = 0;
};

// Mean and standard error of the emitted flux samples at 550 nm (times what
// `weight` returns for the ray), with or without aiming at `target`.
template <typename Weight>
FluxEstimate mean_flux(const Light& light, const GeometryScene& scene, int count, uint64_t seed, Weight weight,
                       const EmissionTarget* target = nullptr) {
  Rng rng(test_seed(seed), 0);
  double sum = 0, sum2 = 0;
  for (int i = 0; i < count; ++i) {
    const Point2 u_position{rng.uniform(), rng.uniform()}, u_direction{rng.uniform(), rng.uniform()};
    const auto e = sample_emission(light, u_position, u_direction, 550.f, scene, target, rng.uniform());
    if (!e) continue;
    const double flux = e->flux * double(weight(*e));
    sum += flux;
    sum2 += flux * flux;
  }
  const double mean = sum / count;
  return {mean, std::sqrt(std::max(0.0, sum2 / count - mean * mean) / count)};
}

// One light of every kind around a unit sphere at the origin; `quad` (at z = 3,
// facing -z) is the area lights' shape. The spot points past the sphere.
std::vector<Light> every_kind(int quad) {
  return {
      PointLight{{0, 0, 5}, Spectrum::constant(2.f), 1.5f},
      SpotLight{{0, 0, 5}, {1, 1, -1}, std::cos(10.f * kPi / 180), std::cos(40.f * kPi / 180), Spectrum::constant(2.f),
                1.5f},
      AreaLight{quad, Spectrum::constant(2.f), 1.5f, false},
      AreaLight{quad, Spectrum::constant(2.f), 1.5f, true},
      DistantLight{{0, 1, -3}, Spectrum::constant(2.f), 1.5f},
      EnvironmentLight{Spectrum::constant(2.f), 1.5f},
  };
}

// phi_power over one nanometre of a constant spectrum: the power per nm.
double power_per_nm(const Light& light, const GeometryScene& scene) { return phi_power(light, scene, 550.f, 551.f); }

}  // namespace

// The mean flux of the emitted rays is the light's power (W/nm), for every kind.
TEST(LightEmission, MeanFluxIsTheLightsPower) {
  GeometryScene scene;
  const int quad = scene.add_mesh(make_quad({-1, -0.5f, 3}, {0, 1, 0}, {2, 0, 0}));  // faces -z
  scene.add_sphere({0, 0, 0}, 1.f);
  scene.commit();
  const float radius = 0.5f * length(scene.bounds().diagonal());
  std::vector<Light> lights = every_kind(quad);
  for (size_t k = 0; k < lights.size(); ++k) {
    Light& light = lights[k];
    preprocess(light, scene.bounds());
    const auto check = [&](const LightEmission& e) {
      EXPECT_NEAR(length(e.ray.d), 1.f, 1e-5f);
      if (const auto* area = std::get_if<AreaLight>(&light)) {
        EXPECT_NEAR(e.ray.o.z, 3.f, 1e-4f) << "leaves the quad";
        if (!area->two_sided) EXPECT_LT(e.ray.d.z, 0.f) << "toward the emitting side";
      }
      if (std::holds_alternative<DistantLight>(light) || std::holds_alternative<EnvironmentLight>(light))
        EXPECT_GE(distance(e.ray.o, scene.bounds().center()), radius * 0.999f) << "from outside the scene";
      if (const auto* spot = std::get_if<SpotLight>(&light)) EXPECT_GE(dot(e.ray.d, spot->direction), spot->cos_falloff_end - 1e-5f);
      return 1.f;
    };
    const double power = power_per_nm(light, scene);
    const FluxEstimate f = mean_flux(light, scene, 200000, 40 + k, check);
    EXPECT_NEAR(f.mean, power, 4 * f.sigma + 1e-5 * power) << "light " << k;
    // Aiming half the rays at the unit sphere leaves every emitted direction covered.
    const EmissionTarget target{{0, 0, 0}, 1.f, 0.5f};
    const FluxEstimate aimed = mean_flux(light, scene, 200000, 50 + k, check, &target);
    EXPECT_NEAR(aimed.mean, power, 4 * aimed.sigma + 1e-5 * power) << "light " << k << " aimed";
  }
}

// Aimed at a sphere, a light sends the same flux into it as without aiming, with
// less noise where the light sees the sphere (the first spot points past it: its
// aimed rays carry nothing and the mixture weight doubles the others).
TEST(LightEmission, AimingAtATargetKeepsTheFluxIntoItAndCutsItsNoise) {
  GeometryScene scene;
  const int quad = scene.add_mesh(make_quad({-1, -0.5f, 3}, {0, 1, 0}, {2, 0, 0}));  // faces -z
  scene.add_sphere({0, 0, 0}, 1.f);
  scene.commit();
  const Vec3 centre{0.3f, -0.2f, 0.1f};
  const float target_radius = 0.4f;
  std::vector<Light> lights = every_kind(quad);
  lights.push_back(SpotLight{{0, 0, 5}, {0, 0, -1}, std::cos(10.f * kPi / 180), std::cos(40.f * kPi / 180),
                             Spectrum::constant(2.f), 1.5f});  // this one sees the target
  // The flux a ray carries into the target sphere.
  const auto into_target = [&](const LightEmission& e) {
    const Vec3 to = centre - e.ray.o;
    const float along = dot(to, e.ray.d);
    return along > 0.f && dot(to, to) - along * along <= target_radius * target_radius ? 1.f : 0.f;
  };
  for (size_t k = 0; k < lights.size(); ++k) {
    Light& light = lights[k];
    preprocess(light, scene.bounds());
    const EmissionTarget target{centre, target_radius, 0.5f};
    const FluxEstimate plain = mean_flux(light, scene, 400000, 60 + k, into_target);
    const FluxEstimate aimed = mean_flux(light, scene, 400000, 70 + k, into_target, &target);
    const double sigma = std::hypot(plain.sigma, aimed.sigma);
    EXPECT_NEAR(aimed.mean, plain.mean, 4 * sigma + 1e-6 * plain.mean) << "light " << k;
    if (k == 1) {
      EXPECT_EQ(plain.mean, 0.0) << "the first spot points past the target";
      continue;
    }
    EXPECT_GT(plain.mean, 0.0) << "light " << k;
    EXPECT_LT(aimed.sigma, 0.5 * plain.sigma) << "light " << k;
  }
}

// Distant light: rays travel along the beam and cross the scene's disk uniformly,
// so the share through a unit square at the centre is its area over π r².
TEST(LightEmission, DistantRaysCoverTheScenesDiskUniformly) {
  GeometryScene scene;
  scene.add_sphere({0, 0, 0}, 2.f);
  scene.commit();
  Light light = DistantLight{{0, 0, -1}, Spectrum::constant(1.f), 1.f};
  preprocess(light, scene.bounds());
  const float r = std::get<DistantLight>(light).scene_radius;
  Rng rng(test_seed(7), 0);
  const int count = 100000;
  int inside = 0;
  for (int i = 0; i < count; ++i) {
    const auto e = sample_emission(light, {rng.uniform(), rng.uniform()}, {rng.uniform(), rng.uniform()}, 550.f, scene);
    ASSERT_TRUE(e);
    ASSERT_EQ(e->ray.d, Vec3(0, 0, -1));
    const Vec3 at_z0 = e->ray.o + e->ray.d * (e->ray.o.z / -e->ray.d.z);
    inside += std::fabs(at_z0.x) < 0.5f && std::fabs(at_z0.y) < 0.5f;
  }
  const double p = 1.0 / (kPi * r * r);
  EXPECT_NEAR(inside, count * p, 4 * std::sqrt(count * p * (1 - p)));
}
