#pragma once
// Lambertian diffuse reflector, two-sided: it reflects on whichever side wo is.
#include <optional>

#include "core/sampling.h"
#include "materials/bsdf_sample.h"
#include "spectra/spectrum.h"

namespace chlorovdb {

struct Diffuse {
  Spectrum albedo;  // directional-hemispherical reflectance in [0, 1]
};

// Local shading space: z is the shading normal.
struct DiffuseBxdf {
  SampledSpectrum R;  // albedo at the path's wavelengths

  SampledSpectrum f(Vec3 wo, Vec3 wi) const;
  float pdf(Vec3 wo, Vec3 wi) const;
  // Cosine-weighted in wo's hemisphere: f |cos| / pdf = R exactly.
  std::optional<BsdfSample> sample(Vec3 wo, Point2 u) const;
};

}  // namespace chlorovdb
