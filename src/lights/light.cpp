#include "lights/light.h"

#include <type_traits>

namespace chlorovdb {

void preprocess(Light& light, const Bounds3& scene_bounds) {
  const float radius = scene_bounds.empty() ? 0.f : 0.5f * length(scene_bounds.diagonal());
  std::visit(
      [&](auto& l) {
        using T = std::decay_t<decltype(l)>;
        if constexpr (std::is_same_v<T, SpotLight> || std::is_same_v<T, DistantLight>)
          l.direction = normalize(l.direction);
        if constexpr (std::is_same_v<T, DistantLight> || std::is_same_v<T, EnvironmentLight>) l.scene_radius = radius;
      },
      light);
}

std::optional<LightLiSample> sample_Li(const Light& light, const LightSampleContext& ctx, Point2 u,
                                       const SampledWavelengths& lambda, const GeometryScene& scene) {
  return std::visit([&](const auto& l) { return sample_Li(l, ctx, u, lambda, scene); }, light);
}

float pdf_Li(const Light& light, const LightSampleContext& ctx, Vec3 wi, const GeometryScene& scene,
             const SurfaceHit* hit_on_light) {
  if (const auto* area = std::get_if<AreaLight>(&light)) return pdf_Li(*area, ctx, wi, scene, hit_on_light);
  if (const auto* env = std::get_if<EnvironmentLight>(&light)) return pdf_Li(*env, ctx, wi);
  return 0.f;  // delta lights cannot be hit by a sampled direction
}

const Spectrum& emission_spectrum(const Light& light) {
  return std::visit(
      [](const auto& l) -> const Spectrum& {
        using T = std::decay_t<decltype(l)>;
        if constexpr (std::is_same_v<T, PointLight> || std::is_same_v<T, SpotLight>) return l.I;
        else if constexpr (std::is_same_v<T, AreaLight>) return l.Le;
        else return l.L;
      },
      light);
}

float light_scale(const Light& light) {
  return std::visit([](const auto& l) { return l.scale; }, light);
}

float phi_power(const Light& light, const GeometryScene& scene, float lambda_min_nm, float lambda_max_nm) {
  return std::visit(
      [&](const auto& l) {
        using T = std::decay_t<decltype(l)>;
        if constexpr (std::is_same_v<T, AreaLight>) return phi_power(l, scene, lambda_min_nm, lambda_max_nm);
        else return phi_power(l, lambda_min_nm, lambda_max_nm);
      },
      light);
}

}  // namespace chlorovdb
