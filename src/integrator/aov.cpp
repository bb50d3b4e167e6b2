#include "integrator/aov.h"

#include <cmath>

#include "integrator/transport.h"
#include "materials/bsdf.h"

namespace chlorovdb {

namespace {

// Smooth glass faces followed for the albedo before giving up (a ray caught between faces).
constexpr int kMaxSpecularFaces = 16;
constexpr int kMaxCrossings = 256;

// An interface (or an interface-only box) is not something the camera sees; an emitter is.
bool is_visible(const Scene& scene, const ShapeBinding& b) { return !is_pass_through(scene, b) || b.area_light >= 0; }

}  // namespace

AovSample trace_aovs(const Scene& scene, const Ray& camera_ray, int medium, const SampledWavelengths& lambda, Rng& rng,
                     AovMask mask) {
  AovSample a;
  Ray ray = camera_ray;
  int faces = 0;
  for (int crossings = 0; crossings < kMaxCrossings; ++crossings) {
    const auto hit = scene.geometry.intersect(ray, kInfinity);
    if (!hit) break;
    const ShapeBinding& b = scene.shapes[hit->shape_id];
    if (!is_visible(scene, b)) {
      ray = scene.geometry.spawn_ray(*hit, ray.d);
      continue;
    }
    if (!a.surface) {
      // The first visible surface: the camera ray is straight up to here (interfaces do not bend it).
      a.surface = true;
      a.depth = dot(hit->p - camera_ray.o, normalize(camera_ray.d));
      a.normal = dot(hit->ng, ray.d) > 0.f ? -hit->ns : hit->ns;
      if (!(mask & kAovAlbedo)) break;
    }
    if (b.material < 0) break;  // an emitter without a material: albedo 0
    const Material& material = scene.materials[b.material];
    if (const auto* diffuse = std::get_if<Diffuse>(&material)) {
      a.albedo = diffuse->albedo.sample(lambda);
      break;
    }
    // Smooth glass: follow its refraction (the sample keeps reflection only where R = 1, total internal reflection).
    if (++faces > kMaxSpecularFaces) break;
    SampledWavelengths lanes = lambda;  // a dispersive refraction would drop the secondaries: keep the film's
    const Bsdf bsdf = make_bsdf(material, *hit, lanes);
    const auto s = bsdf.sample(-ray.d, std::nextafter(1.f, 0.f), Point2{0.5f, 0.5f});
    if (!s) break;
    ray = scene.geometry.spawn_ray(*hit, s->wi);
  }
  if ((mask & kAovAlpha) && !a.surface) {
    PreparedMedia media(scene, lambda);
    ConnectionOptions options;  // opaque and glass surfaces block; none lies on this ray
    a.transmittance = connect_to_light(scene, ShadowOrigin{camera_ray.o, medium, nullptr},
                                       LightTarget{normalize(camera_ray.d), {}, true}, media, rng, options)
                          .T;
  }
  return a;
}

}  // namespace chlorovdb
