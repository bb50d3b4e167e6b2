#pragma once
// Uniform radiance from every direction at infinity (overcast sky, furnace tests).
#include <optional>

#include "core/sampling.h"
#include "geometry/geometry_scene.h"
#include "lights/light_sample.h"
#include "spectra/spectrum.h"

namespace chlorovdb {

struct EnvironmentLight {
  Spectrum L;  // radiance, W/(m²·sr·nm)
  float scale = 1.f;
  float scene_radius = 0.f;  // metres, set by preprocess
};

// Radiance arriving along -dir (seen when looking toward dir).
SampledSpectrum Le_environment(const EnvironmentLight& light, Vec3 dir, const SampledWavelengths& lambda);
// Uniform over the sphere (pdf 1/4π): valid for surfaces of any sidedness and for points in media.
std::optional<LightLiSample> sample_Li(const EnvironmentLight& light, const LightSampleContext& ctx, Point2 u,
                                       const SampledWavelengths& lambda, const GeometryScene& scene);
float pdf_Li(const EnvironmentLight& light, const LightSampleContext& ctx, Vec3 wi);
// Power entering the scene's bounding sphere: L · 4π · π r².
float phi_power(const EnvironmentLight& light, float lambda_min_nm, float lambda_max_nm);

}  // namespace chlorovdb
