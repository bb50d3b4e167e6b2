#pragma once
// Light sources: plain data in a variant, one file per type, behaviour as free
// functions dispatched once per call with std::visit (no virtual calls).
// Every light has an emission Spectrum and a dimensionless scale.
#include <optional>
#include <variant>

#include "lights/area_light.h"
#include "lights/distant_light.h"
#include "lights/environment_light.h"
#include "lights/light_sample.h"
#include "lights/point_light.h"
#include "lights/spot_light.h"

namespace chlorovdb {

using Light = std::variant<PointLight, SpotLight, DistantLight, AreaLight, EnvironmentLight>;

// Point, spot and distant lights: a single direction from any point, so no
// sampled direction (BSDF, phase function, continuation) ever reaches them.
inline bool is_delta(const Light& light) {
  return std::holds_alternative<PointLight>(light) || std::holds_alternative<SpotLight>(light) ||
         std::holds_alternative<DistantLight>(light);
}

// Where a light at a point (point, spot) is; nullopt for any other light.
inline std::optional<Vec3> light_position(const Light& light) {
  if (const auto* point = std::get_if<PointLight>(&light)) return point->position;
  if (const auto* spot = std::get_if<SpotLight>(&light)) return spot->position;
  return std::nullopt;
}

// Once after the scene is built: normalises directions, and gives lights at
// infinity the scene's bounding sphere (for shadow-ray end points and power).
void preprocess(Light& light, const Bounds3& scene_bounds);

std::optional<LightLiSample> sample_Li(const Light& light, const LightSampleContext& ctx, Point2 u,
                                       const SampledWavelengths& lambda, const GeometryScene& scene);
// Solid-angle density with which sample_Li would produce wi; 0 for delta lights.
// hit_on_light: where a BSDF-sampled ray along wi hit this (area) light, if known.
float pdf_Li(const Light& light, const LightSampleContext& ctx, Vec3 wi, const GeometryScene& scene,
             const SurfaceHit* hit_on_light);

const Spectrum& emission_spectrum(const Light& light);  // I, L or Le, depending on the type
float light_scale(const Light& light);
// Approximate emitted power, W, over [lambda_min_nm, lambda_max_nm] (for light
// selection; restrict the band to pick lights for an excitation range).
float phi_power(const Light& light, const GeometryScene& scene, float lambda_min_nm = kLambdaMinUV,
                float lambda_max_nm = kLambdaMax);

}  // namespace chlorovdb
