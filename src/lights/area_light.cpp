#include "lights/area_light.h"

#include <cmath>

namespace chlorovdb {

SampledSpectrum Le_area(const AreaLight& light, Vec3 n_light, Vec3 w_out, const SampledWavelengths& lambda) {
  if (!light.two_sided && dot(n_light, w_out) <= 0.f) return SampledSpectrum(0.f);
  return light.Le.sample(lambda) * light.scale;
}

std::optional<LightLiSample> sample_Li(const AreaLight& light, const LightSampleContext& ctx, Point2 u,
                                       const SampledWavelengths& lambda, const GeometryScene& scene) {
  const ShapeSample ss = scene.sample_area(light.shape_id, u);
  const Vec3 to_light = ss.p - ctx.p;
  const float r2 = length_squared(to_light);
  if (r2 == 0.f) return std::nullopt;
  const Vec3 wi = to_light / std::sqrt(r2);
  const float cos_light = std::fabs(dot(ss.n, wi));
  if (cos_light == 0.f) return std::nullopt;
  const SampledSpectrum Le = Le_area(light, ss.n, -wi, lambda);
  if (Le.is_black()) return std::nullopt;
  // dA = r² / |cos θ_light| dω.
  return LightLiSample{Le, wi, ss.pdf_area * r2 / cos_light, ss.p, false, false, ss.n};
}

float pdf_Li(const AreaLight& light, const LightSampleContext& ctx, Vec3 wi, const GeometryScene& scene,
             const SurfaceHit* hit_on_light) {
  std::optional<SurfaceHit> traced;
  if (!hit_on_light) {
    traced = scene.intersect({ctx.p, wi}, kInfinity);
    if (!traced || traced->shape_id != light.shape_id) return 0.f;
    hit_on_light = &*traced;
  }
  const Vec3 to_light = hit_on_light->p - ctx.p;
  const float r2 = length_squared(to_light);
  const float cos_light = std::fabs(dot(hit_on_light->ng, to_light)) / std::sqrt(r2);
  if (r2 == 0.f || cos_light == 0.f) return 0.f;
  return r2 / (cos_light * scene.area(light.shape_id));
}

float phi_power(const AreaLight& light, const GeometryScene& scene, float lambda_min_nm, float lambda_max_nm) {
  // Lambertian: M = π Le per unit area, per side.
  return light.scale * light.Le.integral(lambda_min_nm, lambda_max_nm) * kPi * scene.area(light.shape_id) *
         (light.two_sided ? 2.f : 1.f);
}

}  // namespace chlorovdb
