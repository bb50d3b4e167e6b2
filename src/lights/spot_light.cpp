#include "lights/spot_light.h"

#include <algorithm>

namespace chlorovdb {

static float smooth_step(float x, float a, float b) {
  if (a == b) return x < a ? 0.f : 1.f;
  const float t = std::clamp((x - a) / (b - a), 0.f, 1.f);
  return t * t * (3.f - 2.f * t);
}

float spot_falloff(const SpotLight& light, Vec3 w) {
  return smooth_step(dot(w, light.direction), light.cos_falloff_end, light.cos_falloff_start);
}

std::optional<LightLiSample> sample_Li(const SpotLight& light, const LightSampleContext& ctx, Point2,
                                       const SampledWavelengths& lambda, const GeometryScene&) {
  const Vec3 to_light = light.position - ctx.p;
  const float r2 = length_squared(to_light);
  if (r2 == 0.f) return std::nullopt;
  const Vec3 wi = to_light / std::sqrt(r2);
  const float falloff = spot_falloff(light, -wi);
  if (falloff == 0.f) return std::nullopt;
  return LightLiSample{light.I.sample(lambda) * (light.scale * falloff / r2), wi, 1.f, light.position, true, false};
}

float phi_power(const SpotLight& light, float lambda_min_nm, float lambda_max_nm) {
  // 2π ∫ falloff(cosθ) dcosθ: 1 over the inner cap, and the smoothstep integrates
  // to half the width of the transition band.
  const float solid_angle =
      2.f * kPi * ((1.f - light.cos_falloff_start) + 0.5f * (light.cos_falloff_start - light.cos_falloff_end));
  return light.scale * light.I.integral(lambda_min_nm, lambda_max_nm) * solid_angle;
}

}  // namespace chlorovdb
