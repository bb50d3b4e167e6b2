#include "integrator/transport.h"

#include <cmath>

#include "tracking/roulette.h"
#include "tracking/sample_t_maj.h"

namespace chlorovdb {

namespace {

// The first shadow-ray segment: offset off the origin surface if there is one.
Ray first_segment(const Scene& scene, const ShadowOrigin& from, const Vec3& wi, const Vec3& p_light, bool to_infinity,
                  float* t_max) {
  if (to_infinity) {
    *t_max = kInfinity;
    return from.hit ? scene.geometry.spawn_ray(*from.hit, wi) : Ray{from.p, wi};
  }
  if (from.hit) return scene.geometry.spawn_ray_to(*from.hit, p_light, t_max);
  *t_max = 1.f;
  return Ray{from.p, p_light - from.p};
}

// Next segment after crossing `hit` toward the light.
Ray next_segment(const Scene& scene, const SurfaceHit& hit, const Vec3& wi, const Vec3& p_light, bool to_infinity,
                 float* t_max) {
  if (to_infinity) {
    *t_max = kInfinity;
    return scene.geometry.spawn_ray(hit, wi);
  }
  return scene.geometry.spawn_ray_to(hit, p_light, t_max);
}

// The smooth dielectric faces a straight-through excitation ray crossed, in the
// order it met them (from the medium point toward the light).
struct DielectricFaces {
  static constexpr int kMax = 16;
  Vec3 ng[kMax];
  float ior[kMax];  // relative IOR, n_inside / n_outside of the face
  int count = 0;
};

}  // namespace

float straight_through_transmission(const Vec3* ng, const float* ior, int count, const Vec3& wi) {
  // The light travels along v = -wi, the direction it has in the light's own
  // medium: the angle at each face is the one a ray from the light refracted by
  // every face before it would have (Snell applied to the direction, not the
  // position). Testing each face at the unrefracted angle instead found total
  // internal reflection at a glass-air face whenever the light was more than
  // 41.8° off its normal, although light coming from air never reflects totally.
  Vec3 v = -normalize(wi);
  float weight = 1.f;
  for (int k = count - 1; k >= 0; --k) {
    const bool entering = dot(v, ng[k]) < 0.f;  // moving against the outward normal
    const Vec3 n = entering ? ng[k] : -ng[k];   // faces the light's side
    const float eta = entering ? ior[k] : 1.f / ior[k];  // n on x's side / n on the light's side
    const float cos_i = std::min(1.f, -dot(v, n));
    const float sin2_t = std::max(0.f, 1.f - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.f) return 0.f;  // total internal reflection, seen from the light's side
    const float cos_t = std::sqrt(1.f - sin2_t);
    // Fresnel transmission, and the beam's compression: the flux through a patch
    // of the face, E cos_i, arrives as E' cos_t, so fluence (and the irradiance
    // of a collimated beam) changes by cos_i / cos_t. For parallel planar faces
    // both factors are those of the exact refracted path.
    weight *= (1.f - fresnel_dielectric(cos_i, eta)) * (cos_i / std::max(cos_t, 1e-6f));
    v = normalize(v / eta + (cos_i / eta - cos_t) * n);
  }
  return weight;
}

namespace {
}  // namespace

LightConnection connect_to_light(const Scene& scene, const ShadowOrigin& from, const LightTarget& to,
                                 PreparedMedia& media, Rng& rng, const ConnectionOptions& options) {
  LightConnection c;
  auto blocked = [&c] {
    c.T = SampledSpectrum(0.f);
    c.blocked = true;
    return c;
  };
  float t_max;
  Ray ray = first_segment(scene, from, to.wi, to.p_light, to.to_infinity, &t_max);
  int medium = from.medium;
  const SampledWavelengths& lambda = media.lambda();
  DielectricFaces faces;
  for (int crossings = 0; crossings < 256; ++crossings) {
    const auto hit = scene.geometry.intersect(ray, t_max);
    if (hit) {
      const ShapeBinding& b = scene.shapes[hit->shape_id];
      if (!is_pass_through(scene, b)) {
        const auto* glass = std::get_if<Dielectric>(&scene.materials[b.material]);
        if (!glass || options.dielectrics == DielectricCrossing::block || faces.count == DielectricFaces::kMax)
          return blocked();
        faces.ng[faces.count] = hit->ng;
        faces.ior[faces.count++] = ior_at(*glass, lambda[0]);
      }
    }
    if (medium >= 0) {
      const float t_end = hit ? hit->t : t_max;
      if (options.mis && !scene.track_by_transmittance(medium)) {
        // Ratio tracking inside the null-scattering framework: every tentative
        // collision multiplies by sigma_n/sigma_maj (pbrt-v4 SampleLd).
        const SampledSpectrum T_maj = sample_T_maj(
            ray, t_end, rng.uniform(), rng, lambda, scene.media[medium], media[medium],
            [&](const Vec3&, const MediumCollision& mc, const SampledSpectrum& sigma_maj,
                const MajorantTransmittance& T_maj) {
              const SampledSpectrum T_m = T_maj();
              const SampledSpectrum sigma_n = clamp_zero(sigma_maj - mc.sigma_t());
              const float pdf = T_m[0] * sigma_maj[0];
              c.T *= T_m * sigma_n / pdf;
              c.r_l *= T_m * sigma_maj / pdf;
              c.r_u *= T_m * sigma_n / pdf;
              const SampledSpectrum Tr = safe_div(c.T, SampledSpectrum(0.5f) * (c.r_l + c.r_u));
              if (const float q = roulette_survival(Tr.max_value()); q < 1.f) {
                if (rng.uniform() < q)
                  c.T /= q;
                else
                  c.T = SampledSpectrum(0.f);
              }
              return !c.T.is_black();
            });
        c.T *= T_maj / T_maj[0];
        c.r_l *= T_maj / T_maj[0];
        c.r_u *= T_maj / T_maj[0];
      } else {
        // Absorbing-only media (as the camera path treats them) and connections
        // without MIS: a plain transmittance weight.
        const TransmittanceEstimator estimator = options.forced ? *options.forced : scene.transmittance_estimator(medium);
        c.T *= transmittance(ray, t_end, lambda, scene.media[medium], media[medium], estimator, rng);
      }
      if (c.T.is_black()) return blocked();
    }
    if (!hit) {
      if (faces.count) c.T *= straight_through_transmission(faces.ng, faces.ior, faces.count, to.wi);
      if (c.T.is_black()) return blocked();
      return c;
    }
    medium = medium_after_crossing(scene.shapes[hit->shape_id], hit->ng, ray.d);
    ray = next_segment(scene, *hit, to.wi, to.p_light, to.to_infinity, &t_max);
  }
  return blocked();  // more crossings than any sane scene has: treat as occluded
}

}  // namespace chlorovdb
