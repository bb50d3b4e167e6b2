#include "media/pigment.h"

#include <cmath>
#include <fmt/format.h>

#include "core/error.h"

namespace chlorovdb {
namespace {

// The smallest value a spectrum takes (its table, or its constant); NaN if any value is NaN.
float min_value(const Spectrum& s) {
  if (const auto* t = std::get_if<Spectrum::Tabulated>(&s.representation())) {
    float m = INFINITY;
    for (float v : t->value) m = std::isnan(v) ? v : std::min(m, v);
    return m * s.scale();
  }
  if (const auto* c = std::get_if<Spectrum::Constant>(&s.representation())) return c->value * s.scale();
  return 0.f;  // blackbody and Gaussian spectra are non-negative by construction
}

}  // namespace

void validate(const Pigment& p, std::string_view file, std::string_view key) {
  const std::string where(key);
  if (!(min_value(p.epsilon) >= 0.f) || !std::isfinite(p.epsilon.max_value()))
    throw InputError(file, where + ".epsilon", p.epsilon.source(),
                     "molar extinction must be finite and >= 0 at every wavelength");
  if (!(p.quantum_yield >= 0.f && p.quantum_yield <= 1.f))
    throw InputError(file, where + ".quantum_yield", fmt::format("{}", p.quantum_yield), "must be in [0, 1]");
  if (!(min_value(p.emission) >= 0.f) || !std::isfinite(p.emission.max_value()))
    throw InputError(file, where + ".emission", p.emission.source(),
                     "emission spectrum must be finite and >= 0 at every wavelength");
  const float integral = p.emission.integral(p.emission.support_min(), p.emission.support_max());
  if (integral == 0.f) {
    if (p.quantum_yield > 0.f)
      throw InputError(file, where + ".emission", p.emission.source(),
                       "is zero but the quantum yield is > 0: a fluorescent pigment needs an emission spectrum");
    return;
  }
  if (std::fabs(integral - 1.f) > 1e-3f)
    throw InputError(file, where + ".emission", p.emission.source(),
                     fmt::format("integrates to {} per nm; it must be normalised to 1", integral));
}

float molar_per_unit(std::string_view unit, std::string_view file, std::string_view key) {
  if (unit == "M" || unit == "mol/L") return 1.f;
  if (unit == "mM") return 1e-3f;
  if (unit == "uM" || unit == "µM") return 1e-6f;
  if (unit == "nM") return 1e-9f;
  throw InputError(file, key, unit, "unknown concentration unit; use M, mM, uM (µM) or nM");
}

}  // namespace chlorovdb
