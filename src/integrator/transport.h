#pragma once
// Shared machinery of the path tracer: media prepared for the path's
// wavelengths, and shadow rays that cross interface surfaces and media.
#include <array>
#include <optional>
#include <vector>

#include "core/rng.h"
#include "scene/scene.h"

namespace chlorovdb {

// Media prepared lazily for one set of wavelengths: a collision then costs a
// concentration lookup and a few multiply-adds per lane.
class PreparedMedia {
 public:
  PreparedMedia(const Scene& scene, const SampledWavelengths& lambda) : scene_(&scene), lambda_(&lambda) {}
  const PreparedMedium& operator[](int medium) {
    std::optional<PreparedMedium>* slot;
    if (medium < kInline) {
      slot = &inline_[medium];
    } else {
      if (overflow_.empty()) overflow_.resize(scene_->media.size() - kInline);
      slot = &overflow_[medium - kInline];
    }
    if (!*slot) *slot = prepare(scene_->media[medium], *lambda_);
    return **slot;
  }
  const SampledWavelengths& lambda() const { return *lambda_; }

 private:
  // One per camera path: the first media live in place, so a path allocates
  // nothing (two allocations per path were 4 % of the cloud benchmark).
  static constexpr int kInline = 2;
  const Scene* scene_;
  const SampledWavelengths* lambda_;
  std::array<std::optional<PreparedMedium>, kInline> inline_;
  std::vector<std::optional<PreparedMedium>> overflow_;
};

// Medium on the far side of a surface crossed in direction `d`: ng points to
// the outside of a closed mesh, so moving against it means entering.
inline int medium_after_crossing(const ShapeBinding& b, const Vec3& ng, const Vec3& d) {
  return dot(d, ng) < 0.f ? b.medium_inside : b.medium_outside;
}

// True when a surface only separates media (no reflection, no refraction).
inline bool is_pass_through(const Scene& scene, const ShapeBinding& b) {
  return b.material < 0 || is_interface(scene.materials[b.material]);
}

// A shadow ray's start: a point, the medium it lies in, and (for surface
// points) the hit, so the ray can be offset off that surface.
struct ShadowOrigin {
  Vec3 p;
  int medium = -1;
  const SurfaceHit* hit = nullptr;
};

// Result of ratio tracking toward a light with the MIS ratios of the
// null-scattering path integral (pbrt-v4 SampleLd): contribution weight is
// T_ray / (r_u + r_l).average() after the caller multiplies in its pdfs.
struct ShadowMis {
  SampledSpectrum T_ray{1.f}, r_u{1.f}, r_l{1.f};
  bool blocked = false;
};

// Toward `p_light` (finite) or along `wi` to infinity. Opaque and refracting
// surfaces block; interface surfaces are crossed, switching media.
ShadowMis trace_shadow_mis(const Scene& scene, const ShadowOrigin& from, const Vec3& wi, const Vec3& p_light,
                           bool to_infinity, PreparedMedia& media, Rng& rng);

// What a shadow ray does at a smooth dielectric surface.
enum class DielectricCrossing {
  block,                       // exact for point/distant lights: refraction cannot be aimed
  straight_through_fresnel,    // thin-walled glass approximation: keep direction, weight by 1-R
};

// The straight_through_fresnel weight of a chain of smooth dielectric faces
// (outward normals ng, relative IORs n_inside/n_outside) met in this order by a
// ray leaving a medium point along wi toward a light: per face, the Fresnel
// transmission at the angle of the light refracted by the faces between it and
// the light, times the beam compression cos_i/cos_t. Exact for parallel planar
// faces except for the ray's lateral shift, its bent path length inside the
// media, and light reflected between faces. 0 under total internal reflection.
float straight_through_transmission(const Vec3* ng, const float* ior, int count, const Vec3& wi);

// Transmittance toward a light (no MIS) at the wavelengths of `media`, with
// the scene's estimator unless `forced` names one. Used for delta lights and
// excitation rays.
SampledSpectrum trace_transmittance(const Scene& scene, const ShadowOrigin& from, const Vec3& wi,
                                    const Vec3& p_light, bool to_infinity, PreparedMedia& media, Rng& rng,
                                    DielectricCrossing dielectrics,
                                    std::optional<TransmittanceEstimator> forced = std::nullopt);

// The estimator the settings ask for in `medium` (closed form if homogeneous under `auto`).
TransmittanceEstimator estimator_for(const Scene& scene, int medium);

}  // namespace chlorovdb
