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

// Where a connection ends: a sampled point on a light, or a direction to
// infinity (distant and environment lights).
struct LightTarget {
  Vec3 wi;        // from the origin toward the light
  Vec3 p_light;   // the point on the light (ignored when to_infinity)
  bool to_infinity = false;
};

// What a connection does at a smooth dielectric surface.
enum class DielectricCrossing {
  block,                       // exact for point/distant lights: refraction cannot be aimed
  straight_through_fresnel,    // thin-walled glass approximation (straight_through_transmission)
};

struct ConnectionOptions {
  DielectricCrossing dielectrics = DielectricCrossing::block;
  // Camera next-event estimation toward a non-delta light: in media tracked by
  // collisions, ratio tracking inside the null-scattering framework with the
  // MIS ratios of pbrt-v4's SampleLd, so light and phase/BSDF sampling combine.
  // Otherwise (and always in media tracked by transmittance) T comes from the
  // scene's transmittance estimator and r_u = r_l = 1.
  bool mis = false;
  std::optional<TransmittanceEstimator> forced;  // replaces the scene's estimator outside the MIS tracking
};

// A connection's result: the throughput T of its legs (medium transmittance
// times interface weights) and the null-scattering MIS ratios. With MIS the
// caller's weight is T / (r_u·p_scatter + r_l·p_light).average(); without, T.
struct LightConnection {
  SampledSpectrum T{1.f}, r_u{1.f}, r_l{1.f};
  bool blocked = false;
};

// The one routine that connects a point in a medium or on a surface to a
// light through media and surfaces: camera next-event estimation and
// fluorescence excitation rays both call it. Opaque surfaces block; interfaces
// are crossed, switching media; smooth dielectrics follow options.dielectrics.
// Russian roulette follows the tracking's single policy (tracking/roulette.h).
LightConnection connect_to_light(const Scene& scene, const ShadowOrigin& from, const LightTarget& to,
                                 PreparedMedia& media, Rng& rng, const ConnectionOptions& options);

// The straight_through_fresnel weight of a chain of smooth dielectric faces
// (outward normals ng, relative IORs n_inside/n_outside) met in this order by a
// ray leaving a medium point along wi toward a light: per face, the Fresnel
// transmission at the angle of the light refracted by the faces between it and
// the light, times the beam compression cos_i/cos_t. Exact for parallel planar
// faces except for the ray's lateral shift, its bent path length inside the
// media, and light reflected between faces. 0 under total internal reflection.
float straight_through_transmission(const Vec3* ng, const float* ior, int count, const Vec3& wi);

}  // namespace chlorovdb
