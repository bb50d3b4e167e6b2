#pragma once
// Phase functions as plain data in a std::variant (dispatched once per
// scattering event, no virtual calls), each sampled exactly: pdf == value.
// Directions follow pbrt-v4: wo and wi both point away from the scattering point.
#include <variant>

#include "core/sampling.h"
#include "core/vec.h"
#include "media/henyey_greenstein.h"
#include "media/rayleigh_phase.h"
#include "spectra/sampled.h"

namespace chlorovdb {

struct Isotropic {};
struct Rayleigh {};
struct HenyeyGreenstein {
  float g = 0.f;  // mean cosine of the scattering angle, in (-1, 1)
};
using PhaseFunction = std::variant<Isotropic, Rayleigh, HenyeyGreenstein>;

struct PhaseSample {
  Vec3 wi;
  float p = 0.f;    // phase function value, 1/sr
  float pdf = 0.f;  // solid-angle density of wi (equal to p: exact sampling)
};

// Value of p for the cosine between wo and wi.
inline float phase_eval(const PhaseFunction& phase, float cos_theta) {
  struct {
    float c;
    float operator()(Isotropic) const { return kInv4Pi; }
    float operator()(Rayleigh) const { return rayleigh_phase(c); }
    float operator()(HenyeyGreenstein hg) const { return henyey_greenstein(c, hg.g); }
  } eval{cos_theta};
  return std::visit(eval, phase);
}
inline float phase_eval(const PhaseFunction& phase, const Vec3& wo, const Vec3& wi) {
  return phase_eval(phase, dot(wo, wi));
}
inline float phase_pdf(const PhaseFunction& phase, const Vec3& wo, const Vec3& wi) { return phase_eval(phase, wo, wi); }

inline PhaseSample phase_sample(const PhaseFunction& phase, const Vec3& wo, Point2 u) {
  struct {
    float u0;
    float operator()(Isotropic) const { return 1.f - 2.f * u0; }
    float operator()(Rayleigh) const { return sample_rayleigh_cos_theta(u0); }
    float operator()(HenyeyGreenstein hg) const { return sample_henyey_greenstein_cos_theta(u0, hg.g); }
  } sample_cos{u.x};
  const float cos_theta = std::visit(sample_cos, phase);
  const float sin_theta = std::sqrt(std::max(0.f, 1.f - cos_theta * cos_theta));
  const float phi = 2.f * kPi * u.y;
  const Vec3 wi = Frame::from_z(wo).to_world({sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta});
  const float p = phase_eval(phase, cos_theta);
  return {wi, p, p};
}

}  // namespace chlorovdb
