#include "lights/environment_light.h"

namespace chlorovdb {

SampledSpectrum Le_environment(const EnvironmentLight& light, Vec3, const SampledWavelengths& lambda) {
  return light.L.sample(lambda) * light.scale;
}

std::optional<LightLiSample> sample_Li(const EnvironmentLight& light, const LightSampleContext& ctx, Point2 u,
                                       const SampledWavelengths& lambda, const GeometryScene&) {
  const Vec3 wi = sample_uniform_sphere(u);
  return LightLiSample{Le_environment(light, wi, lambda), wi, uniform_sphere_pdf(),
                       ctx.p + wi * (2.f * light.scene_radius), false, true};
}

float pdf_Li(const EnvironmentLight&, const LightSampleContext&, Vec3) { return uniform_sphere_pdf(); }

float phi_power(const EnvironmentLight& light, float lambda_min_nm, float lambda_max_nm) {
  return light.scale * light.L.integral(lambda_min_nm, lambda_max_nm) * 4.f * kPi * kPi * light.scene_radius *
         light.scene_radius;
}

}  // namespace chlorovdb
