#include "integrator/transport.h"

#include <cmath>

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

TransmittanceEstimator estimator_for(const Scene& scene, int medium) {
  if (scene.settings.transmittance_auto) return automatic_transmittance_estimator(scene.media[medium]);
  if (scene.settings.transmittance == TransmittanceEstimator::closed_form && !is_homogeneous(scene.media[medium]))
    return TransmittanceEstimator::residual_ratio;
  return scene.settings.transmittance;
}

ShadowMis trace_shadow_mis(const Scene& scene, const ShadowOrigin& from, const Vec3& wi, const Vec3& p_light,
                           bool to_infinity, PreparedMedia& media, Rng& rng) {
  ShadowMis s;
  float t_max;
  Ray ray = first_segment(scene, from, wi, p_light, to_infinity, &t_max);
  int medium = from.medium;
  const SampledWavelengths& lambda = media.lambda();
  for (int crossings = 0; crossings < 256; ++crossings) {
    const auto hit = scene.geometry.intersect(ray, t_max);
    if (hit && !is_pass_through(scene, scene.shapes[hit->shape_id])) {
      s.blocked = true;
      return s;
    }
    if (medium >= 0 && scene.track_by_transmittance(medium)) {
      // As the camera path does in absorbing-only media: a plain weight.
      s.T_ray *= transmittance(ray, hit ? hit->t : t_max, lambda, scene.media[medium], media[medium],
                               estimator_for(scene, medium), rng);
      if (s.T_ray.is_black()) {
        s.blocked = true;
        return s;
      }
    } else if (medium >= 0) {
      const float t_end = hit ? hit->t : t_max;
      // Ratio tracking inside the null-scattering framework: every tentative
      // collision multiplies by sigma_n/sigma_maj (pbrt-v4 SampleLd).
      const SampledSpectrum T_maj = sample_T_maj(
          ray, t_end, rng.uniform(), rng, lambda, scene.media[medium], media[medium],
          [&](const Vec3&, const MediumCollision& c, const SampledSpectrum& sigma_maj, const MajorantTransmittance& T_maj) {
            const SampledSpectrum T_m = T_maj();
            const SampledSpectrum sigma_n = clamp_zero(sigma_maj - c.sigma_t());
            const float pdf = T_m[0] * sigma_maj[0];
            s.T_ray *= T_m * sigma_n / pdf;
            s.r_l *= T_m * sigma_maj / pdf;
            s.r_u *= T_m * sigma_n / pdf;
            // Russian roulette on low transmittance keeps thick media cheap.
            const SampledSpectrum Tr = safe_div(s.T_ray, SampledSpectrum(0.5f) * (s.r_l + s.r_u));
            if (Tr.max_value() < 0.05f) {
              if (rng.uniform() < 0.75f)
                s.T_ray = SampledSpectrum(0.f);
              else
                s.T_ray /= 0.25f;
            }
            return !s.T_ray.is_black();
          });
      s.T_ray *= T_maj / T_maj[0];
      s.r_l *= T_maj / T_maj[0];
      s.r_u *= T_maj / T_maj[0];
      if (s.T_ray.is_black()) {
        s.blocked = true;
        return s;
      }
    }
    if (!hit) return s;
    medium = medium_after_crossing(scene.shapes[hit->shape_id], hit->ng, ray.d);
    ray = next_segment(scene, *hit, wi, p_light, to_infinity, &t_max);
  }
  s.blocked = true;  // more crossings than any sane scene has: treat as occluded
  return s;
}

SampledSpectrum trace_transmittance(const Scene& scene, const ShadowOrigin& from, const Vec3& wi, const Vec3& p_light,
                                    bool to_infinity, PreparedMedia& media, Rng& rng, DielectricCrossing dielectrics,
                                    std::optional<TransmittanceEstimator> forced) {
  SampledSpectrum T(1.f);
  float t_max;
  Ray ray = first_segment(scene, from, wi, p_light, to_infinity, &t_max);
  int medium = from.medium;
  const SampledWavelengths& lambda = media.lambda();
  DielectricFaces faces;
  for (int crossings = 0; crossings < 256; ++crossings) {
    const auto hit = scene.geometry.intersect(ray, t_max);
    if (hit) {
      const ShapeBinding& b = scene.shapes[hit->shape_id];
      if (!is_pass_through(scene, b)) {
        const auto* glass = std::get_if<Dielectric>(&scene.materials[b.material]);
        if (!glass || dielectrics == DielectricCrossing::block || faces.count == DielectricFaces::kMax)
          return SampledSpectrum(0.f);
        faces.ng[faces.count] = hit->ng;
        faces.ior[faces.count++] = ior_at(*glass, lambda[0]);
      }
    }
    if (medium >= 0) {
      const float t_end = hit ? hit->t : t_max;
      const TransmittanceEstimator estimator = forced ? *forced : estimator_for(scene, medium);
      T *= transmittance(ray, t_end, lambda, scene.media[medium], media[medium], estimator, rng);
      if (T.is_black()) return T;
    }
    if (!hit) return faces.count ? T * straight_through_transmission(faces.ng, faces.ior, faces.count, wi) : T;
    medium = medium_after_crossing(scene.shapes[hit->shape_id], hit->ng, ray.d);
    ray = next_segment(scene, *hit, wi, p_light, to_infinity, &t_max);
  }
  return SampledSpectrum(0.f);
}

}  // namespace chlorovdb
