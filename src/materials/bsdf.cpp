#include "materials/bsdf.h"

#include <cmath>
#include <type_traits>

namespace chlorovdb {

SampledSpectrum Bsdf::f(Vec3 wo, Vec3 wi) const {
  if (const auto* d = std::get_if<DiffuseBxdf>(&bxdf_)) return d->f(shading_.to_local(wo), shading_.to_local(wi));
  return SampledSpectrum(0.f);
}

float Bsdf::pdf(Vec3 wo, Vec3 wi) const {
  if (const auto* d = std::get_if<DiffuseBxdf>(&bxdf_)) return d->pdf(shading_.to_local(wo), shading_.to_local(wi));
  return 0.f;
}

std::optional<BsdfSample> Bsdf::sample(Vec3 wo, float uc, Point2 u) const {
  if (const auto* d = std::get_if<DiffuseBxdf>(&bxdf_)) {
    auto s = d->sample(shading_.to_local(wo), u);
    if (s) s->wi = shading_.to_world(s->wi);
    return s;
  }
  // Which side is "outside" (and so which way eta goes) is the geometric
  // normal's call. Where an interpolated shading normal disagrees with it about
  // wo's side, the geometric frame is used so entering/leaving stays consistent.
  const bool shading_agrees = (dot(wo, shading_.n) > 0.f) == (dot(wo, ng_) > 0.f);
  const Frame frame = shading_agrees ? shading_ : Frame::from_z(ng_);
  const Vec3 wo_local = frame.to_local(wo);
  auto s = std::holds_alternative<DielectricBxdf>(bxdf_)
               ? std::get<DielectricBxdf>(bxdf_).sample(wo_local, uc, lambda_)
               : std::get<InterfaceBxdf>(bxdf_).sample(wo_local);
  if (!s) return s;
  const float cos_frame = std::fabs(s->wi.z);
  s->wi = frame.to_world(s->wi);
  if (!shading_agrees) {
    // The delta's weight f·|cos| was made in the geometric frame; callers apply
    // |cos(wi, ns)| (BsdfSample), so restate f for that cosine. Otherwise each
    // grazing reflection inside a smooth-shaded glass wall would gain
    // |cos(wi, ns)| / |cos(wi, ng)| (up to ~12× on the beaker) along a light guide.
    const float cos_shading = std::fabs(dot(s->wi, shading_.n));
    if (!(cos_shading > 0.f)) return std::nullopt;
    s->f *= cos_frame / cos_shading;
  }
  return s;
}

Bsdf make_bsdf(const Material& material, const SurfaceHit& hit, SampledWavelengths& lambda) {
  const Frame shading = Frame::from_z(hit.ns);
  return std::visit(
      [&](const auto& m) -> Bsdf {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, Diffuse>) {
          return Bsdf(shading, hit.ng, DiffuseBxdf{m.albedo.sample(lambda)}, &lambda);
        } else if constexpr (std::is_same_v<T, Dielectric>) {
          SampledSpectrum eta(0.f);
          for (int i = 0; i < lambda.count(); ++i) eta[i] = ior_at(m, lambda[i]);
          return Bsdf(shading, hit.ng, DielectricBxdf{eta, is_dispersive(m)}, &lambda);
        } else {
          return Bsdf(shading, hit.ng, InterfaceBxdf{}, &lambda);
        }
      },
      material);
}

}  // namespace chlorovdb
