#pragma once
// The phase function at a point where molecules (Rayleigh) and particles both
// scatter. Per wavelength it is the mixture
//   p_lambda = (1 - f_lambda) p_Rayleigh + f_lambda p_particle,  f_lambda = sigma_s,particle / sigma_s,
// and f changes across the carried wavelengths (molecular scattering goes as
// lambda^-4), so the value is per lane. One direction serves all lanes: it is
// drawn from the mixture with the hero lane's weights, whose pdf is positive
// wherever any lane's p is (Rayleigh and HG are positive everywhere), so
// every lane stays unbiased with weight p_lambda / pdf.
#include "media/phase.h"
#include "spectra/sampled.h"

namespace chlorovdb {

struct MediumPhase {
  PhaseFunction particle = Isotropic{};
  SampledSpectrum particle_fraction;  // f per lane; 0 where only molecules scatter (or nothing does)
};

struct MediumPhaseSample {
  Vec3 wi;
  SampledSpectrum p;  // per-lane phase value, 1/sr
  float pdf = 0.f;    // solid-angle density of wi
};

inline SampledSpectrum phase_eval(const MediumPhase& phase, const Vec3& wo, const Vec3& wi) {
  const float c = dot(wo, wi);
  const float p_molecular = rayleigh_phase(c), p_particle = phase_eval(phase.particle, c);
  return SampledSpectrum(p_molecular) + phase.particle_fraction * (p_particle - p_molecular);
}

inline float phase_pdf(const MediumPhase& phase, const Vec3& wo, const Vec3& wi) {
  const float c = dot(wo, wi), f = phase.particle_fraction[0];
  return (1.f - f) * rayleigh_phase(c) + f * phase_eval(phase.particle, c);
}

// u.x picks the component (and is reused, rescaled, for its cos theta); u.y gives phi.
inline MediumPhaseSample phase_sample(const MediumPhase& phase, const Vec3& wo, Point2 u) {
  const float f = phase.particle_fraction[0];
  PhaseSample s;
  if (u.x < f) s = phase_sample(phase.particle, wo, {std::min(u.x / f, 0x1.fffffep-1f), u.y});
  else s = phase_sample(PhaseFunction(Rayleigh{}), wo, {std::min((u.x - f) / (1.f - f), 0x1.fffffep-1f), u.y});
  return {s.wi, phase_eval(phase, wo, s.wi), phase_pdf(phase, wo, s.wi)};
}

}  // namespace chlorovdb
