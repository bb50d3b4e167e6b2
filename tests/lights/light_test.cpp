#include <gtest/gtest.h>

#include <cmath>

#include "core/constants.h"
#include "core/rng.h"
#include "lights/light.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

namespace {

const SampledWavelengths kLambda = SampledWavelengths::single(550.f);

// Irradiance at ctx (normal n) estimated from `count` light samples: Σ L |cos| / pdf, one-sided.
double irradiance(const Light& light, const LightSampleContext& ctx, const GeometryScene& scene, int count,
                  uint64_t seed) {
  Rng rng(test_seed(seed), 0);
  double sum = 0;
  for (int i = 0; i < count; ++i) {
    const auto ls = sample_Li(light, ctx, {rng.uniform(), rng.uniform()}, kLambda, scene);
    if (!ls) continue;
    sum += ls->L[0] * std::max(0.f, dot(ls->wi, ctx.n)) / ls->pdf;
  }
  return sum / count;
}

// Differential area to a parallel rectangle, receiver below one corner:
// F = 1/(2π) [ A/√(1+A²) atan(B/√(1+A²)) + B/√(1+B²) atan(A/√(1+B²)) ], A = a/h, B = b/h.
double corner_form_factor(double a, double b, double h) {
  const double A = a / h, B = b / h, sa = std::sqrt(1 + A * A), sb = std::sqrt(1 + B * B);
  return (A / sa * std::atan(B / sa) + B / sb * std::atan(A / sb)) / (2 * M_PI);
}

struct QuadLightScene {
  GeometryScene scene;
  Light light;
  QuadLightScene(float Le, bool two_sided) {
    // 2 x 1 m quad at z = 3 facing down (-z), centred above the origin.
    const int id = scene.add_mesh(make_quad({-1, -0.5f, 3}, {0, 1, 0}, {2, 0, 0}));
    scene.commit();
    light = AreaLight{id, Spectrum::constant(Le), 1.f, two_sided};
  }
};

}  // namespace

TEST(PointLight, InverseSquareIrradiance) {
  GeometryScene scene;
  scene.commit();
  const Light light = PointLight{{1, 2, 5}, Spectrum::constant(3.f), 2.f};
  const LightSampleContext ctx{{1, 0, 1}, normalize(Vec3{0, 1, 1})};
  const auto ls = sample_Li(light, ctx, {0.5f, 0.5f}, kLambda, scene);
  ASSERT_TRUE(ls);
  EXPECT_TRUE(ls->is_delta);
  EXPECT_FALSE(ls->is_infinite);
  EXPECT_EQ(ls->pdf, 1.f);
  EXPECT_EQ(ls->p_light, Vec3(1, 2, 5));
  const float r2 = 4 + 16, cos = dot(normalize(Vec3{0, 2, 4}), ctx.n);
  EXPECT_NEAR(irradiance(light, ctx, scene, 1, 1), 6.f / r2 * cos, 1e-6);
  EXPECT_EQ(pdf_Li(light, ctx, ls->wi, scene, nullptr), 0.f);
  EXPECT_NEAR(phi_power(light, scene, 400.f, 500.f), 4 * kPi * 2 * 3 * 100, 1e-2);
  EXPECT_EQ(light_scale(light), 2.f);
  EXPECT_EQ(emission_spectrum(light)(600.f), 3.f);
}

TEST(SpotLight, FalloffLimits) {
  SpotLight spot{{0, 0, 0}, {0, 0, -2}, std::cos(20.f * kPi / 180), std::cos(30.f * kPi / 180),
                 Spectrum::constant(1.f), 1.f};
  Light light = spot;
  preprocess(light, {});
  spot = std::get<SpotLight>(light);
  auto at = [&](float degrees) {
    const float t = degrees * kPi / 180;
    return spot_falloff(spot, {std::sin(t), 0, -std::cos(t)});
  };
  EXPECT_EQ(at(0), 1.f);
  EXPECT_EQ(at(19.9f), 1.f);
  EXPECT_EQ(at(30.1f), 0.f);
  EXPECT_EQ(at(90), 0.f);
  EXPECT_GT(at(24), at(26));
  EXPECT_GT(at(25), 0.f);
  EXPECT_LT(at(25), 1.f);
  // Outside the cone no light arrives at all.
  GeometryScene scene;
  scene.commit();
  EXPECT_FALSE(sample_Li(light, {{0, 5, -1}, {0, 0, 1}}, {0.5f, 0.5f}, kLambda, scene));
  const auto inside = sample_Li(light, {{0, 0, -4}, {0, 0, 1}}, {0.5f, 0.5f}, kLambda, scene);
  ASSERT_TRUE(inside);
  EXPECT_NEAR(inside->L[0], 1.f / 16, 1e-7f);
}

TEST(SpotLight, PowerMatchesIntegratedFalloff) {
  Light light = SpotLight{{0, 0, 0}, {1, 1, 0}, std::cos(10.f * kPi / 180), std::cos(40.f * kPi / 180),
                          Spectrum::constant(2.f), 1.5f};
  preprocess(light, {});
  GeometryScene scene;
  scene.commit();
  // The falloff's solid angle, 2 pi \int falloff d(cos theta), by a midpoint rule over
  // directions around the axis: deterministic, where a Monte Carlo estimate within a fixed
  // 1 % was only 1.6 of its own standard errors (a seed sweep failed it).
  const SpotLight& spot = std::get<SpotLight>(light);
  const Frame frame = Frame::from_z(spot.direction);
  const int steps = 200000;
  double integral = 0;
  for (int i = 0; i < steps; ++i) {
    const double cos_theta = -1.0 + 2.0 * (i + 0.5) / steps;
    const double sin_theta = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
    integral += spot_falloff(spot, frame.to_world(Vec3{float(sin_theta), 0.f, float(cos_theta)}));
  }
  const double solid_angle = 2 * M_PI * integral * 2.0 / steps;
  EXPECT_NEAR(phi_power(light, scene, 500.f, 501.f), 1.5 * 2 * solid_angle, 1e-4 * 3 * solid_angle);
}

TEST(DistantLight, CollimatedIrradiance) {
  GeometryScene scene;
  scene.commit();
  Light light = DistantLight{{0, 0, -3}, Spectrum::constant(10.f), 0.5f};
  preprocess(light, {{-1, -1, -1}, {1, 1, 1}});
  const LightSampleContext ctx{{0.2f, 0.3f, 0}, normalize(Vec3{1, 0, 1})};
  const auto ls = sample_Li(light, ctx, {0.1f, 0.9f}, kLambda, scene);
  ASSERT_TRUE(ls);
  EXPECT_TRUE(ls->is_delta);
  EXPECT_TRUE(ls->is_infinite);
  EXPECT_EQ(ls->wi, Vec3(0, 0, 1));
  EXPECT_GT(distance(ls->p_light, ctx.p), 2 * std::sqrt(3.f) - 1e-5f) << "shadow-ray end outside the scene";
  EXPECT_NEAR(irradiance(light, ctx, scene, 1, 2), 5.f * std::sqrt(0.5f), 1e-6);
  EXPECT_NEAR(phi_power(light, scene, 400.f, 410.f), 0.5 * 10 * 10 * M_PI * 3, 1e-2);
}

TEST(AreaLight, QuadIrradianceMatchesTheFormFactor) {
  QuadLightScene q(2.f, false);
  const LightSampleContext ctx{{0, 0, 0}, {0, 0, 1}};
  // Centred receiver: four corner rectangles of 1 x 0.5 m at height 3 m.
  const double expected = 2.0 * M_PI * 4 * corner_form_factor(1.0, 0.5, 3.0);
  EXPECT_NEAR(irradiance(q.light, ctx, q.scene, 200000, 3), expected, 0.005 * expected);
}

TEST(AreaLight, TiltedReceiverMatchesBruteForceHemisphereSampling) {
  QuadLightScene q(1.f, false);
  const LightSampleContext ctx{{0.7f, -0.4f, 0.5f}, normalize(Vec3{0.5f, 0.2f, 1})};
  // Reference: cosine-sample the hemisphere of n and look the radiance up by ray casting.
  const Frame frame = Frame::from_z(ctx.n);
  Rng rng(test_seed(4), 0);
  const int count = 1000000;
  double brute = 0;
  for (int i = 0; i < count; ++i) {
    const Vec3 wi = frame.to_world(sample_cosine_hemisphere({rng.uniform(), rng.uniform()}));
    const auto hit = q.scene.intersect({ctx.p, wi}, kInfinity);
    if (hit) brute += Le_area(std::get<AreaLight>(q.light), hit->ng, -wi, kLambda)[0] * kPi;  // L cos / (cos/π)
  }
  brute /= count;
  const double light_sampled = irradiance(q.light, ctx, q.scene, 200000, 5);
  EXPECT_NEAR(light_sampled, brute, 0.01 * brute);
}

TEST(AreaLight, OneSidedEmitsOnlyTowardItsNormal) {
  QuadLightScene one(1.f, false), two(1.f, true);
  const LightSampleContext above{{0, 0, 6}, {0, 0, -1}};
  EXPECT_EQ(irradiance(one.light, above, one.scene, 1000, 6), 0.0);
  EXPECT_GT(irradiance(two.light, above, two.scene, 1000, 6), 0.0);
  EXPECT_NEAR(phi_power(two.light, two.scene, 500.f, 600.f), 2 * phi_power(one.light, one.scene, 500.f, 600.f), 1e-3);
  EXPECT_NEAR(phi_power(one.light, one.scene, 500.f, 600.f), 1 * 100 * M_PI * 2, 1e-2);
}

TEST(AreaLight, SphereIrradianceAndPdfConsistency) {
  GeometryScene scene;
  const int id = scene.add_sphere({0, 0, 4}, 1.f);
  scene.commit();
  const Light light = AreaLight{id, Spectrum::constant(1.5f), 1.f, false};
  const LightSampleContext ctx{{0, 0, 0}, {0, 0, 1}};
  // A Lambertian sphere of radius R at distance d, seen face-on: E = π L (R/d)².
  const double expected = M_PI * 1.5 / 16;
  EXPECT_NEAR(irradiance(light, ctx, scene, 400000, 7), expected, 0.01 * expected);

  Rng rng(test_seed(8), 0);
  for (int i = 0; i < 1000; ++i) {
    const auto ls = sample_Li(light, ctx, {rng.uniform(), rng.uniform()}, kLambda, scene);
    if (!ls) continue;
    // At the silhouette a float-rounded sample point can lie just off the sphere: skip grazing ones.
    if (dot(ls->p_light - Vec3(0, 0, 4), -ls->wi) < 1e-2f) continue;
    const auto hit = scene.intersect({ctx.p, ls->wi}, kInfinity);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(distance(hit->p, ls->p_light), 0.f, 1e-4f) << "the sampled point is the visible one";
    EXPECT_NEAR(pdf_Li(light, ctx, ls->wi, scene, &*hit), ls->pdf, 1e-3f * ls->pdf);
    EXPECT_NEAR(pdf_Li(light, ctx, ls->wi, scene, nullptr), ls->pdf, 1e-3f * ls->pdf);
  }
}

TEST(AreaLight, PdfLiMatchesSampleOnAQuadAndIsZeroOffTheLight) {
  QuadLightScene q(1.f, false);
  const LightSampleContext ctx{{0.3f, 0.1f, 0}, {0, 0, 1}};
  Rng rng(test_seed(10), 0);
  for (int i = 0; i < 1000; ++i) {
    const auto ls = sample_Li(q.light, ctx, {rng.uniform(), rng.uniform()}, kLambda, q.scene);
    ASSERT_TRUE(ls);
    EXPECT_NEAR(pdf_Li(q.light, ctx, ls->wi, q.scene, nullptr), ls->pdf, 1e-4f * ls->pdf);
  }
  EXPECT_EQ(pdf_Li(q.light, ctx, {0, 0, -1}, q.scene, nullptr), 0.f);
}

TEST(EnvironmentLight, SurfaceIrradianceIsPiL) {
  GeometryScene scene;
  scene.add_sphere({0, 0, 0}, 1.f);
  scene.commit();
  Light light = EnvironmentLight{Spectrum::constant(0.8f), 2.f};
  preprocess(light, scene.bounds());
  const LightSampleContext ctx{{3, 0, 0}, normalize(Vec3{-1, 1, 1})};
  const double expected = M_PI * 1.6;
  EXPECT_NEAR(irradiance(light, ctx, scene, 400000, 11), expected, 0.01 * expected);
  Rng rng(test_seed(12), 0);
  for (int i = 0; i < 100; ++i) {
    const auto ls = sample_Li(light, ctx, {rng.uniform(), rng.uniform()}, kLambda, scene);
    ASSERT_TRUE(ls);
    EXPECT_TRUE(ls->is_infinite);
    EXPECT_FALSE(ls->is_delta);
    EXPECT_EQ(pdf_Li(light, ctx, ls->wi, scene, nullptr), ls->pdf);
    EXPECT_GT(distance(ls->p_light, ctx.p), 2 * std::sqrt(3.f) - 1e-5f);
  }
  EXPECT_EQ(Le_environment(std::get<EnvironmentLight>(light), {0, 1, 0}, kLambda)[0], 1.6f);
  EXPECT_NEAR(phi_power(light, scene, 500.f, 501.f), 1.6 * 4 * M_PI * M_PI * 3, 1e-3);
}
