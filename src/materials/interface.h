#pragma once
// A medium boundary that neither reflects nor refracts (index-matched): light
// crosses it unchanged and only the medium the path is in changes.
#include <cmath>
#include <optional>

#include "core/vec.h"
#include "materials/bsdf_sample.h"

namespace chlorovdb {

struct Interface {};

// Local-space (z = normal) pass-through: the only direction is wi = -wo, with
// weight f |cos| / pdf = 1. Makes make_bsdf total even though the integrator
// normally skips interfaces via is_interface().
struct InterfaceBxdf {
  std::optional<BsdfSample> sample(Vec3 wo) const {
    if (wo.z == 0.f) return std::nullopt;
    return BsdfSample{SampledSpectrum(1.f / std::fabs(wo.z)), -wo, 1.f, true, true, 1.f};
  }
};

}  // namespace chlorovdb
