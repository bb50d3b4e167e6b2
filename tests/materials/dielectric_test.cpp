#include <gtest/gtest.h>

#include <cmath>

#include "core/constants.h"
#include "core/rng.h"
#include "materials/bsdf.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

namespace {

SurfaceHit up_hit() {
  SurfaceHit hit;
  hit.ng = hit.ns = {0, 0, 1};
  return hit;
}

SampledWavelengths four_wavelengths() {
  const float lambda[4] = {420.f, 510.f, 600.f, 690.f}, pdf[4] = {1.f, 1.f, 1.f, 1.f};
  return SampledWavelengths::from_values(lambda, pdf, 4);
}

const Sellmeier kBK7{{1.03961212f, 0.231792344f, 1.01046945f}, {0.00600069867f, 0.0200179144f, 103.560653f}};

// Fresnel transmittance from the amplitude coefficients, independent of the
// reflectance formula: T = (n_t cos_t)/(n_i cos_i) (|t_s|² + |t_p|²) / 2.
double fresnel_transmittance(double cos_i, double eta) {
  const double sin2_t = (1 - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1) return 0;
  const double cos_t = std::sqrt(1 - sin2_t);
  const double t_s = 2 * cos_i / (cos_i + eta * cos_t);
  const double t_p = 2 * cos_i / (eta * cos_i + cos_t);
  return eta * cos_t / cos_i * 0.5 * (t_s * t_s + t_p * t_p);
}

}  // namespace

TEST(Fresnel, ReflectancePlusTransmittanceIsOne) {
  for (float eta : {1.33f, 1.5f, 2.4f, 1.f / 1.5f}) {
    for (int i = 1; i <= 100; ++i) {
      const float cos_i = i / 100.f;
      const double R = fresnel_dielectric(cos_i, eta);
      EXPECT_NEAR(R + fresnel_transmittance(cos_i, eta), 1.0, 1e-5) << "eta " << eta << " cos " << cos_i;
    }
  }
  EXPECT_NEAR(fresnel_dielectric(1.f, 1.5f), 0.04f, 1e-6f);  // ((n-1)/(n+1))²
  EXPECT_FLOAT_EQ(fresnel_dielectric(0.f, 1.5f), 1.f);        // grazing
  EXPECT_NEAR(fresnel_dielectric(-1.f, 1.5f), 0.04f, 1e-6f);  // from inside, normal incidence
}

TEST(Fresnel, TotalInternalReflectionBeyondTheCriticalAngle) {
  const float eta = 1.5f, cos_critical = std::sqrt(1.f - 1.f / (eta * eta));
  EXPECT_FLOAT_EQ(fresnel_dielectric(-(cos_critical - 1e-3f), eta), 1.f);
  EXPECT_LT(fresnel_dielectric(-(cos_critical + 1e-3f), eta), 1.f);
  EXPECT_FLOAT_EQ(fresnel_dielectric(-0.1f, eta), 1.f);
}

TEST(Dielectric, SamplingSplitsByFresnelAndObeysSnell) {
  SampledWavelengths lambda = four_wavelengths();
  const Bsdf bsdf = make_bsdf(Dielectric{1.5f}, up_hit(), lambda);
  EXPECT_TRUE(bsdf.is_specular());
  const Vec3 wo = normalize(Vec3{0.6f, 0.2f, 0.5f});
  const float R = fresnel_dielectric(wo.z, 1.5f);
  Rng rng(test_seed(4), 0);
  int reflections = 0;
  const int count = 100000;
  for (int i = 0; i < count; ++i) {
    const auto s = bsdf.sample(wo, rng.uniform(), {rng.uniform(), rng.uniform()});
    ASSERT_TRUE(s);
    EXPECT_TRUE(s->is_specular);
    const float weight = s->f[0] * std::fabs(s->wi.z) / s->pdf;
    if (!s->is_transmission) {
      ++reflections;
      EXPECT_NEAR(s->wi.x, -wo.x, 1e-6f);
      EXPECT_NEAR(s->wi.z, wo.z, 1e-6f);
      EXPECT_NEAR(weight, 1.f, 1e-5f);
      EXPECT_EQ(s->eta, 1.f);
    } else {
      EXPECT_LT(s->wi.z, 0.f);
      const float sin_i = std::sqrt(1 - wo.z * wo.z), sin_t = std::sqrt(1 - s->wi.z * s->wi.z);
      EXPECT_NEAR(sin_i, 1.5f * sin_t, 1e-5f);
      EXPECT_NEAR(dot(cross(wo, s->wi), Vec3(0, 0, 1)), 0.f, 1e-6f) << "refracted ray leaves the plane of incidence";
      EXPECT_NEAR(weight, 1.f / (1.5f * 1.5f), 1e-5f) << "radiance scales by 1/eta² entering";
      EXPECT_FLOAT_EQ(s->eta, 1.5f);
    }
    for (int k = 1; k < lambda.count(); ++k) EXPECT_EQ(s->f[k], s->f[0]) << "constant IOR keeps all lanes";
  }
  EXPECT_NEAR(double(reflections) / count, R, 4 * std::sqrt(R * (1 - R) / count));
  EXPECT_FALSE(lambda.secondary_terminated());
  EXPECT_TRUE(bsdf.f(wo, {-wo.x, -wo.y, wo.z}).is_black());
  EXPECT_EQ(bsdf.pdf(wo, {-wo.x, -wo.y, wo.z}), 0.f);
}

TEST(Dielectric, LeavingUsesTheInverseEtaAndReflectsTotallyBeyondCritical) {
  SampledWavelengths lambda = four_wavelengths();
  const Bsdf bsdf = make_bsdf(Dielectric{1.5f}, up_hit(), lambda);
  // wo below the surface (inside the glass), inside the critical cone.
  const Vec3 wo_inside = normalize(Vec3{0.3f, 0, -1});
  const auto t = bsdf.sample(wo_inside, 0.999f, {0.5f, 0.5f});
  ASSERT_TRUE(t);
  ASSERT_TRUE(t->is_transmission);
  EXPECT_GT(t->wi.z, 0.f);
  EXPECT_NEAR(t->eta, 1.f / 1.5f, 1e-6f);
  EXPECT_NEAR(t->f[0] * std::fabs(t->wi.z) / t->pdf, 1.5f * 1.5f, 1e-4f);
  // Beyond the critical angle (41.8°): every sample reflects with weight 1.
  const Vec3 wo_grazing = normalize(Vec3{1, 0, -0.5f});
  Rng rng(test_seed(5), 0);
  for (int i = 0; i < 1000; ++i) {
    const auto s = bsdf.sample(wo_grazing, rng.uniform(), {0.5f, 0.5f});
    ASSERT_TRUE(s);
    EXPECT_FALSE(s->is_transmission);
    EXPECT_LT(s->wi.z, 0.f);
    EXPECT_NEAR(s->f[0] * std::fabs(s->wi.z) / s->pdf, 1.f, 1e-6f);
  }
}

TEST(Dielectric, SellmeierBK7AtTheSodiumDLine) {
  EXPECT_NEAR(sellmeier_ior(kBK7, 587.6f), 1.5168f, 1e-4f);
  EXPECT_GT(sellmeier_ior(kBK7, 450.f), sellmeier_ior(kBK7, 650.f)) << "normal dispersion";
  EXPECT_TRUE(is_dispersive(Dielectric{kBK7}));
  EXPECT_FALSE(is_dispersive(Dielectric{1.5f}));
}

TEST(Dielectric, DispersiveRefractionTerminatesSecondaryWavelengths) {
  const Vec3 wo = normalize(Vec3{0.5f, 0, 1});
  {
    SampledWavelengths lambda = four_wavelengths();
    const Bsdf bsdf = make_bsdf(Dielectric{kBK7}, up_hit(), lambda);
    const auto r = bsdf.sample(wo, 0.f, {0.5f, 0.5f});  // uc = 0: reflection
    ASSERT_TRUE(r);
    ASSERT_FALSE(r->is_transmission);
    EXPECT_FALSE(lambda.secondary_terminated()) << "reflection is the same direction for every wavelength";
    EXPECT_GT(r->f[0], r->f[3]) << "bluer light reflects more (higher IOR)";
  }
  SampledWavelengths lambda = four_wavelengths();
  const Bsdf bsdf = make_bsdf(Dielectric{kBK7}, up_hit(), lambda);
  const auto t = bsdf.sample(wo, 0.999f, {0.5f, 0.5f});
  ASSERT_TRUE(t);
  ASSERT_TRUE(t->is_transmission);
  EXPECT_TRUE(lambda.secondary_terminated());
  EXPECT_FLOAT_EQ(lambda.pdf(0), 0.25f);
  EXPECT_EQ(lambda.pdf(1), 0.f);
  EXPECT_NEAR(t->eta, sellmeier_ior(kBK7, 420.f), 1e-6f) << "the hero wavelength sets the direction";
  EXPECT_EQ(t->f[1], 0.f);
}

TEST(Dielectric, EtaFollowsTheGeometricNormalWhenShadingDisagrees) {
  SurfaceHit hit;
  hit.ng = {0, 0, 1};
  hit.ns = normalize(Vec3{1, 0, 0.2f});  // strongly bent shading normal
  SampledWavelengths lambda = four_wavelengths();
  const Bsdf bsdf = make_bsdf(Dielectric{1.5f}, hit, lambda);
  const Vec3 wo = normalize(Vec3{-1, 0, 0.1f});  // outside by ng, "inside" by ns
  const auto t = bsdf.sample(wo, 0.999f, {0.5f, 0.5f});
  ASSERT_TRUE(t);
  ASSERT_TRUE(t->is_transmission);
  EXPECT_FLOAT_EQ(t->eta, 1.5f);
  EXPECT_LT(dot(t->wi, hit.ng), 0.f);
}

// The path weight f·|cos(wi, ns)|/pdf of a smooth dielectric is R/P(R) = 1 for a
// reflection and T/(η²·P(T)) = 1/η² for a refraction, whichever frame sampled
// it. Where the shading normal disagrees with the geometric one about wo's side
// the geometric frame samples; its f must still be stated for |cos(wi, ns)|.
TEST(Dielectric, PathWeightIsFresnelsWhereShadingDisagrees) {
  Rng rng(test_seed(29), 7);
  int disagreeing = 0;
  for (int i = 0; i < 4000; ++i) {
    SurfaceHit hit;
    hit.ng = {0, 0, 1};
    // Shading normals up to ~40° off the geometric one, as on a coarse lathed beaker.
    hit.ns = normalize(Vec3{0.8f * (rng.uniform() - 0.5f) * 2.f, 0.8f * (rng.uniform() - 0.5f) * 2.f, 1.f});
    // Grazing directions on either side, where the two normals disagree most often.
    const float phi = 2.f * kPi * rng.uniform();
    const float z = (rng.uniform() < 0.5f ? 1.f : -1.f) * 0.2f * rng.uniform();
    const float r = std::sqrt(std::max(0.f, 1.f - z * z));
    const Vec3 wo{r * std::cos(phi), r * std::sin(phi), z};
    if ((dot(wo, hit.ns) > 0.f) != (dot(wo, hit.ng) > 0.f)) ++disagreeing;
    SampledWavelengths lambda = four_wavelengths();
    const Bsdf bsdf = make_bsdf(Dielectric{1.5f}, hit, lambda);
    const auto s = bsdf.sample(wo, rng.uniform(), {0.5f, 0.5f});
    if (!s) continue;
    const float weight = s->f[0] * std::fabs(dot(s->wi, hit.ns)) / s->pdf;
    const float expected = s->is_transmission ? 1.f / (s->eta * s->eta) : 1.f;
    ASSERT_NEAR(weight, expected, 1e-3f * expected) << "wo " << wo.x << " " << wo.y << " " << wo.z << ", ns " << hit.ns.x
                                                    << " " << hit.ns.y << " " << hit.ns.z;
  }
  EXPECT_GT(disagreeing, 200) << "the case under test must occur";
}

TEST(Interface, PassesStraightThrough) {
  const Material m = Interface{};
  EXPECT_TRUE(is_interface(m));
  EXPECT_FALSE(is_interface(Material{Dielectric{1.33f}}));
  SampledWavelengths lambda = four_wavelengths();
  const Bsdf bsdf = make_bsdf(m, up_hit(), lambda);
  const Vec3 wo = normalize(Vec3{0.3f, -0.2f, 0.9f});
  const auto s = bsdf.sample(wo, 0.3f, {0.1f, 0.7f});
  ASSERT_TRUE(s);
  EXPECT_EQ(s->wi, -wo);
  EXPECT_TRUE(s->is_transmission);
  EXPECT_NEAR(s->f[0] * std::fabs(s->wi.z) / s->pdf, 1.f, 1e-6f);
  EXPECT_EQ(s->eta, 1.f);
}
