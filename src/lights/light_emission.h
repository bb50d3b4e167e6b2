#pragma once
// Sampling a ray leaving a light, for tracing photons from the lamps
// (integrator/excitation_photons.h): the light-side twin of sample_Li.
#include <optional>

#include "geometry/geometry_scene.h"
#include "lights/light.h"

namespace chlorovdb {

struct LightEmission {
  Ray ray;     // leaving the light (from outside the scene's bounding sphere for lights at infinity)
  float flux;  // emitted spectral power at λ divided by the ray's density: W/nm per sample
};

// One emitted ray at wavelength λ: point and spot lights uniformly over their
// sphere or outer cone, area lights uniformly by area and cosine-weighted in
// direction (each side with probability ½ if two-sided), distant and environment
// lights through a disk of the scene's bounding radius (environment: uniform
// direction). nullopt where the sample carries nothing.
std::optional<LightEmission> sample_emission(const Light& light, Point2 u_position, Point2 u_direction,
                                             float lambda_nm, const GeometryScene& scene);

}  // namespace chlorovdb
