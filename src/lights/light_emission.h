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
  Vec3 p,
      n;  // the point it leaves (area lights: ray.o is offset off the surface) and the area light's geometric normal
};

// A sphere a share of the emitted rays aims at (the medium the photons are traced
// for): a lamp that sees a small vessel sends most of its own density elsewhere.
// With probability aimed_share a ray leaves toward the sphere (uniformly within the
// cone it subtends from the light's point, or through its disk for lights at
// infinity), otherwise by the light's own density; the flux divides by the
// mixture's density, so every direction the light emits into stays covered and
// light that reaches the sphere off the floor still counts (one-sample MIS).
struct EmissionTarget {
  Vec3 centre;
  float radius = 0.f;
  float aimed_share = 0.5f;
};

// One emitted ray at wavelength λ: point and spot lights uniformly over their
// sphere or outer cone, area lights uniformly by area and cosine-weighted in
// direction (each side with probability ½ if two-sided), distant and environment
// lights through a disk of the scene's bounding radius (environment: uniform
// direction); with a target, mixed with rays toward it (u_aim < aimed_share picks
// the target). nullopt where the sample carries nothing.
std::optional<LightEmission> sample_emission(const Light& light, Point2 u_position, Point2 u_direction,
                                             float lambda_nm, const GeometryScene& scene,
                                             const EmissionTarget* target = nullptr, float u_aim = 1.f);

// The solid-angle density of sample_emission's direction without a target, for
// lights at a point (point: uniform sphere; spot: uniform in the outer cone);
// 0 for any other light.
float emission_direction_pdf(const Light& light, const Vec3& w);
// An area light's: the density of sample_emission's ray (without a target) leaving
// the point of geometric normal n in direction w, per unit area and solid angle.
float emission_area_direction_pdf(const AreaLight& light, const Vec3& n, const Vec3& w, const GeometryScene& scene);

}  // namespace chlorovdb
