#pragma once
// Point source emitting into a cone, with pbrt-v4's smoothstep falloff between
// the inner (full intensity) and outer (zero) cone angles.
#include <optional>

#include "core/sampling.h"
#include "geometry/geometry_scene.h"
#include "lights/light_sample.h"
#include "spectra/spectrum.h"

namespace chlorovdb {

struct SpotLight {
  Vec3 position;            // world space, metres
  Vec3 direction;           // cone axis, the way the light shines (normalised in preprocess)
  float cos_falloff_start;  // cosine of the inner half-angle: full intensity inside
  float cos_falloff_end;    // cosine of the outer half-angle: dark outside (<= cos_falloff_start)
  Spectrum I;               // on-axis radiant intensity, W/(sr·nm)
  float scale = 1.f;
};

// Relative intensity in [0, 1] toward the unit direction w (leaving the light).
float spot_falloff(const SpotLight& light, Vec3 w);
std::optional<LightLiSample> sample_Li(const SpotLight& light, const LightSampleContext& ctx, Point2 u,
                                       const SampledWavelengths& lambda, const GeometryScene& scene);
float phi_power(const SpotLight& light, float lambda_min_nm, float lambda_max_nm);

}  // namespace chlorovdb
