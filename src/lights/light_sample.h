#pragma once
#include "core/vec.h"
#include "spectra/sampled.h"

namespace chlorovdb {

// Where light is being gathered.
struct LightSampleContext {
  Vec3 p;  // world space, metres
  Vec3 n;  // surface normal; the zero vector for points in media (no current light strategy depends on it)
};

// One sampled incident direction from a light.
struct LightLiSample {
  SampledSpectrum L;  // incident radiance W/(m²·sr·nm); for delta lights the delta's weight
                      // (point/spot: I / r², distant: irradiance), so L |cos| / pdf is the contribution
  Vec3 wi;            // unit, from the receiving point toward the light
  float pdf;          // solid-angle density, or 1 for delta lights
  Vec3 p_light;       // point to trace the shadow ray to (outside the scene for infinite lights)
  bool is_delta;      // no MIS with BSDF sampling possible
  bool is_infinite;   // at infinity: test occlusion to the scene's edge, not to p_light exactly
  Vec3 n_light{};     // area lights: the geometric normal at p_light
};

}  // namespace chlorovdb
