#pragma once
// Diffuse (Lambertian) emitter on a shape of the GeometryScene.
#include <optional>

#include "core/sampling.h"
#include "geometry/geometry_scene.h"
#include "lights/light_sample.h"
#include "spectra/spectrum.h"

namespace chlorovdb {

struct AreaLight {
  int shape_id;       // GeometryScene shape that emits
  Spectrum Le;        // emitted radiance, W/(m²·sr·nm)
  float scale = 1.f;
  bool two_sided = false;  // else emits only on the side its geometric normal points to
};

// Radiance leaving a point of the light with geometric normal n_light toward w_out.
SampledSpectrum Le_area(const AreaLight& light, Vec3 n_light, Vec3 w_out, const SampledWavelengths& lambda);

// A point uniform by area, its density converted to solid angle at ctx.p.
std::optional<LightLiSample> sample_Li(const AreaLight& light, const LightSampleContext& ctx, Point2 u,
                                       const SampledWavelengths& lambda, const GeometryScene& scene);
// Solid-angle density of sample_Li producing wi. With hit_on_light (the point a
// BSDF-sampled ray found on this light) no ray is traced; without it the first
// hit along wi decides (0 if it is not this light).
float pdf_Li(const AreaLight& light, const LightSampleContext& ctx, Vec3 wi, const GeometryScene& scene,
             const SurfaceHit* hit_on_light);
float phi_power(const AreaLight& light, const GeometryScene& scene, float lambda_min_nm, float lambda_max_nm);

}  // namespace chlorovdb
