#include "lights/point_light.h"

namespace chlorovdb {

std::optional<LightLiSample> sample_Li(const PointLight& light, const LightSampleContext& ctx, Point2,
                                       const SampledWavelengths& lambda, const GeometryScene&) {
  const Vec3 to_light = light.position - ctx.p;
  const float r2 = length_squared(to_light);
  if (r2 == 0.f) return std::nullopt;
  // Inverse-square law: E_perp = I / r².
  return LightLiSample{light.I.sample(lambda) * (light.scale / r2), to_light / std::sqrt(r2), 1.f, light.position,
                       true, false};
}

float phi_power(const PointLight& light, float lambda_min_nm, float lambda_max_nm) {
  return 4.f * kPi * light.scale * light.I.integral(lambda_min_nm, lambda_max_nm);
}

}  // namespace chlorovdb
