#include "materials/dielectric.h"

#include <cmath>

#include <fmt/format.h>

namespace chlorovdb {

float sellmeier_ior(const Sellmeier& s, float lambda_nm) {
  const double l2 = double(lambda_nm) * lambda_nm * 1e-6;  // µm²
  double n2 = 1.0;
  for (int i = 0; i < 3; ++i) n2 += s.B[i] * l2 / (l2 - s.C[i]);
  return float(std::sqrt(n2));
}

std::optional<std::string> sellmeier_problem(const Sellmeier& s, float lambda_min_nm, float lambda_max_nm) {
  const double lo2 = double(lambda_min_nm) * lambda_min_nm * 1e-6, hi2 = double(lambda_max_nm) * lambda_max_nm * 1e-6;
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(s.B[i]) || !std::isfinite(s.C[i])) return fmt::format("B[{}] and C[{}] must be finite", i, i);
    if (s.B[i] != 0.f && s.C[i] >= lo2 && s.C[i] <= hi2)
      return fmt::format("C[{}] = {:g} um^2 puts a pole of n at {:.1f} nm, inside the rendered spectrum [{:g}, {:g}] nm", i,
                         s.C[i], std::sqrt(double(s.C[i])) * 1e3, lambda_min_nm, lambda_max_nm);
  }
  // Between poles n² is smooth: 1 nm steps find where it leaves the range.
  for (float l = lambda_min_nm; l <= lambda_max_nm; l += 1.f) {
    const double l2 = double(l) * l * 1e-6;
    double n2 = 1.0;
    for (int i = 0; i < 3; ++i) n2 += s.B[i] * l2 / (l2 - s.C[i]);
    if (!(n2 >= 1e-6 && n2 <= 100.0))
      return fmt::format("n^2 = {:.4g} at {:g} nm: the index must be real and in [0.001, 10] over [{:g}, {:g}] nm", n2, l,
                         lambda_min_nm, lambda_max_nm);
  }
  return std::nullopt;
}

float ior_at(const Dielectric& d, float lambda_nm) {
  if (const float* n = std::get_if<float>(&d.ior)) return *n;
  return sellmeier_ior(std::get<Sellmeier>(d.ior), lambda_nm);
}

float fresnel_dielectric(float cos_i, float eta) {
  cos_i = std::clamp(cos_i, -1.f, 1.f);
  if (cos_i < 0.f) {  // arriving from the inside: swap the media
    eta = 1.f / eta;
    cos_i = -cos_i;
  }
  const float sin2_i = 1.f - cos_i * cos_i;
  const float sin2_t = sin2_i / (eta * eta);
  if (sin2_t >= 1.f) return 1.f;  // total internal reflection
  const float cos_t = std::sqrt(std::max(0.f, 1.f - sin2_t));
  const float r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  const float r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  return 0.5f * (r_parl * r_parl + r_perp * r_perp);
}

bool refract(Vec3 w, Vec3 n, float eta, Vec3* wt, float* eta_crossed) {
  float cos_i = dot(n, w);
  if (cos_i < 0.f) {
    eta = 1.f / eta;
    cos_i = -cos_i;
    n = -n;
  }
  const float sin2_t = std::max(0.f, 1.f - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.f) return false;
  const float cos_t = std::sqrt(1.f - sin2_t);
  *wt = -w / eta + (cos_i / eta - cos_t) * n;
  *eta_crossed = eta;
  return true;
}

std::optional<BsdfSample> DielectricBxdf::sample(Vec3 wo, float uc, SampledWavelengths* lambda) const {
  if (wo.z == 0.f) return std::nullopt;
  const float R = fresnel_dielectric(wo.z, eta[0]), T = 1.f - R;
  if (uc < R / (R + T)) {
    // Mirror reflection: the direction is the same for every wavelength, so all
    // lanes stay valid, each with its own Fresnel factor.
    const Vec3 wi{-wo.x, -wo.y, wo.z};
    SampledSpectrum f;
    if (dispersive) {
      for (int i = 0; i < lambda->count(); ++i) f[i] = fresnel_dielectric(wo.z, eta[i]) / std::fabs(wi.z);
    } else {
      f = SampledSpectrum(R / std::fabs(wi.z));
    }
    return BsdfSample{f, wi, R / (R + T), true, false, 1.f};
  }
  Vec3 wi;
  float eta_crossed;
  if (!refract(wo, Vec3{0, 0, 1}, eta[0], &wi, &eta_crossed)) return std::nullopt;  // T > 0 excludes TIR; guards rounding
  SampledSpectrum f(0.f);
  const float ft = T / std::fabs(wi.z) / (eta_crossed * eta_crossed);
  if (dispersive) {
    // Each wavelength would bend differently: keep the hero only.
    lambda->terminate_secondary();
    f[0] = ft;
  } else {
    f = SampledSpectrum(ft);
  }
  return BsdfSample{f, wi, T / (R + T), true, true, eta_crossed};
}

}  // namespace chlorovdb
