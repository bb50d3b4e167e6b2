#pragma once
// Collimated beam from infinity (sunlight, a lab's collimated source).
#include <optional>

#include "core/sampling.h"
#include "geometry/geometry_scene.h"
#include "lights/light_sample.h"
#include "spectra/spectrum.h"

namespace chlorovdb {

struct DistantLight {
  Vec3 direction;  // the way the light travels (normalised in preprocess)
  Spectrum L;      // spectral irradiance on a surface perpendicular to the beam, W/(m²·nm)
  float scale = 1.f;
  float scene_radius = 0.f; // metres, set by preprocess
};

// Delta in direction: LightLiSample::L is the irradiance, pdf = 1.
std::optional<LightLiSample> sample_Li(const DistantLight& light, const LightSampleContext& ctx, Point2 u,
                                       const SampledWavelengths& lambda, const GeometryScene& scene);
// Power through the scene's bounding disk.
float phi_power(const DistantLight& light, float lambda_min_nm, float lambda_max_nm);

}  // namespace chlorovdb
