#pragma once
// The scattering function at one surface interaction: a shading frame plus the
// material's values at the path's wavelengths. A small value type (no
// allocation); all directions are in world space, wo points away from the surface.
#include <optional>
#include <variant>

#include "core/sampling.h"
#include "geometry/geometry_scene.h"
#include "materials/bsdf_sample.h"
#include "materials/material.h"

namespace chlorovdb {

class Bsdf {
 public:
  Bsdf(const Frame& shading, Vec3 ng, std::variant<DiffuseBxdf, DielectricBxdf, InterfaceBxdf> bxdf,
       SampledWavelengths* lambda)
      : shading_(shading), ng_(ng), bxdf_(bxdf), lambda_(lambda) {}

  SampledSpectrum f(Vec3 wo, Vec3 wi) const;  // 0 for specular materials (deltas are only sampled)
  float pdf(Vec3 wo, Vec3 wi) const;          // solid angle; 0 for specular materials
  std::optional<BsdfSample> sample(Vec3 wo, float uc, Point2 u) const;
  // Specular (delta) materials cannot be evaluated or light-sampled.
  bool is_specular() const { return !std::holds_alternative<DiffuseBxdf>(bxdf_); }

 private:
  Frame shading_;
  Vec3 ng_;
  std::variant<DiffuseBxdf, DielectricBxdf, InterfaceBxdf> bxdf_;
  SampledWavelengths* lambda_;  // the path's wavelengths; a dispersive refraction terminates secondaries
};

// Evaluates `material` at `hit` for the path's wavelengths. The Bsdf keeps a
// pointer to `lambda`: use it only while that path state is alive.
Bsdf make_bsdf(const Material& material, const SurfaceHit& hit, SampledWavelengths& lambda);

}  // namespace chlorovdb
