#pragma once
#include "core/vec.h"
#include "spectra/sampled.h"

namespace chlorovdb {

// One sampled scattering direction. The path weight is f * |cos(wi, ns)| / pdf.
struct BsdfSample {
  SampledSpectrum f;  // BSDF value, 1/sr (for specular events: the delta's weight divided by |cos|)
  Vec3 wi;            // unit, pointing away from the surface
  float pdf;          // solid-angle density, or the discrete probability for specular events
  bool is_specular;   // delta distribution: no light sampling / MIS possible
  bool is_transmission;
  float eta;          // relative IOR n_t / n_i crossed on transmission (1 for reflection)
};

}  // namespace chlorovdb
