#include "lights/distant_light.h"

namespace chlorovdb {

std::optional<LightLiSample> sample_Li(const DistantLight& light, const LightSampleContext& ctx, Point2,
                                       const SampledWavelengths& lambda, const GeometryScene&) {
  const Vec3 wi = -light.direction;
  // Twice the scene radius from any point inside the scene is outside it.
  const Vec3 p_outside = ctx.p + wi * (2.f * light.scene_radius);
  return LightLiSample{light.L.sample(lambda) * light.scale, wi, 1.f, p_outside, true, true};
}

float phi_power(const DistantLight& light, float lambda_min_nm, float lambda_max_nm) {
  return light.scale * light.L.integral(lambda_min_nm, lambda_max_nm) * kPi * light.scene_radius *
         light.scene_radius;
}

}  // namespace chlorovdb
