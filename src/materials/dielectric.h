#pragma once
// Smooth dielectric boundary (glass, water surface): specular reflection and
// refraction weighted by the exact Fresnel equations for unpolarised light.
// The IOR is relative: n_inside / n_outside, "outside" being the side the
// geometric normal points to. A Sellmeier IOR disperses light, so a sampled
// refraction keeps only the hero wavelength (SampledWavelengths::terminate_secondary).
#include <array>
#include <optional>
#include <string>
#include <variant>

#include "core/sampling.h"
#include "materials/bsdf_sample.h"
#include "spectra/sampled.h"

namespace chlorovdb {

// n²(λ) = 1 + Σ_i B_i λ² / (λ² - C_i), λ in µm (the form glass catalogues publish).
struct Sellmeier {
  std::array<float, 3> B;  // dimensionless
  std::array<float, 3> C;  // µm²
};

struct Dielectric {
  std::variant<float, Sellmeier> ior;  // constant, or dispersive
};

float sellmeier_ior(const Sellmeier& s, float lambda_nm);
// Why `s` is not a usable IOR over [lambda_min_nm, lambda_max_nm]: a pole
// (C_i = λ² inside the range) or n outside [1e-3, 10] (n² < 0 has no real
// index) somewhere there, the same bounds as a constant "ior". nullopt if usable.
std::optional<std::string> sellmeier_problem(const Sellmeier& s, float lambda_min_nm, float lambda_max_nm);
float ior_at(const Dielectric& d, float lambda_nm);
inline bool is_dispersive(const Dielectric& d) { return std::holds_alternative<Sellmeier>(d.ior); }

// Fresnel reflectance of unpolarised light. cos_i = cos(angle to the normal) on
// the incident side, eta = n_t / n_i for cos_i > 0; a negative cos_i means the
// light arrives from the other side and eta is inverted. Returns 1 under total
// internal reflection.
float fresnel_dielectric(float cos_i, float eta);
// Snell refraction of the unit direction w (pointing away from the surface, on
// the side of the unit normal n when dot(n, w) > 0) across a boundary with
// relative IOR eta (as for fresnel_dielectric). eta_crossed: n_t / n_i along the
// way w came from. False under total internal reflection.
bool refract(Vec3 w, Vec3 n, float eta, Vec3* wt, float* eta_crossed);

// Local space: z is the normal pointing outside. Radiance transport (camera
// paths): transmitted radiance is scaled by 1 / eta² (compressed solid angle).
struct DielectricBxdf {
  SampledSpectrum eta;  // relative IOR per wavelength (all lanes equal unless dispersive)
  bool dispersive;

  // Chooses reflection with probability R / (R + T) at the hero wavelength.
  // A dispersive refraction terminates the secondary wavelengths of *lambda.
  std::optional<BsdfSample> sample(Vec3 wo, float uc, SampledWavelengths* lambda) const;
};

}  // namespace chlorovdb
