#pragma once
// Surface materials: plain data in a variant, one file per member. The
// per-interaction scattering functions are built from them by make_bsdf (bsdf.h).
#include <variant>

#include "materials/dielectric.h"
#include "materials/diffuse.h"
#include "materials/interface.h"

namespace chlorovdb {

using Material = std::variant<Diffuse, Dielectric, Interface>;

// Interfaces only switch the current medium: the integrator passes straight
// through them without counting a bounce.
inline bool is_interface(const Material& m) { return std::holds_alternative<Interface>(m); }

}  // namespace chlorovdb
