#pragma once
// First-hit compositing quantities (AOVs) of one camera ray, with the semantics
// production renderers use (Cycles, Arnold; OIDN for the albedo):
//  - visible surface: the first surface along the camera ray that is not an
//    interface (index-matched medium boundaries, a grid's bounding box): any
//    material other than `interface`, or an emitter. Media are not surfaces.
//  - depth: the distance along the camera ray to it (metres; not camera-space z).
//  - normal: its world-space shading normal, flipped to face the camera.
//  - albedo: the reflectance of the first non-specular surface, following smooth
//    glass through its refraction (its reflection under total internal reflection;
//    dispersive glass along the hero wavelength's refraction), as a denoiser wants
//    the texture seen through glass; emitters and escaping rays have albedo 0.
//  - transmittance: when no visible surface is met, the transmittance of the media
//    along the camera ray to the background (crossing interfaces), by the scene's
//    transmittance estimator; the film's alpha is 1 − its ȳ-weighted value.
#include "core/rng.h"
#include "film/film.h"
#include "scene/scene.h"

namespace chlorovdb {

// `medium` is the camera's; `rng` is used only for the transmittance of `mask`'s alpha.
AovSample trace_aovs(const Scene& scene, const Ray& ray, int medium, const SampledWavelengths& lambda, Rng& rng, AovMask mask);

}  // namespace chlorovdb
