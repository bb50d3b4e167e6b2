#pragma once
// Isotropic point source.
#include <optional>

#include "core/sampling.h"
#include "geometry/geometry_scene.h"
#include "lights/light_sample.h"
#include "spectra/spectrum.h"

namespace chlorovdb {

struct PointLight {
  Vec3 position;  // world space, metres
  Spectrum I;     // radiant intensity, W/(sr·nm)
  float scale = 1.f;
};

std::optional<LightLiSample> sample_Li(const PointLight& light, const LightSampleContext& ctx, Point2 u,
                                       const SampledWavelengths& lambda, const GeometryScene& scene);
float phi_power(const PointLight& light, float lambda_min_nm, float lambda_max_nm);

}  // namespace chlorovdb
