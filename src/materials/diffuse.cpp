#include "materials/diffuse.h"

#include "core/constants.h"

namespace chlorovdb {

static bool same_hemisphere(Vec3 a, Vec3 b) { return a.z * b.z > 0.f; }

SampledSpectrum DiffuseBxdf::f(Vec3 wo, Vec3 wi) const {
  return same_hemisphere(wo, wi) ? R * kInvPi : SampledSpectrum(0.f);
}

float DiffuseBxdf::pdf(Vec3 wo, Vec3 wi) const {
  return same_hemisphere(wo, wi) ? cosine_hemisphere_pdf(std::fabs(wi.z)) : 0.f;
}

std::optional<BsdfSample> DiffuseBxdf::sample(Vec3 wo, Point2 u) const {
  if (wo.z == 0.f) return std::nullopt;
  Vec3 wi = sample_cosine_hemisphere(u);
  if (wo.z < 0.f) wi.z = -wi.z;
  const float pdf = cosine_hemisphere_pdf(std::fabs(wi.z));
  if (pdf == 0.f) return std::nullopt;  // u on the disk's rim: grazing, carries no energy
  return BsdfSample{R * kInvPi, wi, pdf, false, false, 1.f};
}

}  // namespace chlorovdb
