#include "lights/light_emission.h"

#include <cmath>
#include <limits>

#include "core/sampling.h"

namespace chlorovdb {

namespace {

// The cone of directions from p that meet the target sphere.
struct TargetCone {
  Frame frame;  // z toward the sphere's centre
  float cos_max;
  float pdf;  // uniform over the cone
  float density(const Vec3& w) const { return dot(w, frame.n) >= cos_max ? pdf : 0.f; }
};

// nullopt from inside the sphere, where there is nothing to aim at.
std::optional<TargetCone> cone_toward(const EmissionTarget& target, const Vec3& p) {
  const Vec3 to = target.centre - p;
  const float d2 = dot(to, to), r2 = target.radius * target.radius;
  if (!(d2 > r2) || !(target.radius > 0.f)) return std::nullopt;
  const float sin2 = r2 / d2;
  const float one_minus_cos = sin2 / (1.f + std::sqrt(1.f - sin2));  // no cancellation for small cones
  return TargetCone{Frame::from_z(to / std::sqrt(d2)), 1.f - one_minus_cos, 1.f / (2.f * kPi * one_minus_cos)};
}

struct MixedDirection {
  Vec3 w;
  float pdf;  // solid-angle density of the mixture at w
};

// A direction leaving p: toward the target with probability aimed_share, else
// from the light's own density (own_sample(u) → w, own_pdf(w)).
template <typename OwnSample, typename OwnPdf>
std::optional<MixedDirection> mixed_direction(const EmissionTarget* target, const Vec3& p, Point2 u_dir, float u_aim,
                                              OwnSample own_sample, OwnPdf own_pdf) {
  const std::optional<TargetCone> cone = target ? cone_toward(*target, p) : std::nullopt;
  if (!cone) {
    const std::optional<Vec3> w = own_sample(u_dir);
    if (!w) return std::nullopt;
    return MixedDirection{*w, own_pdf(*w)};
  }
  const float share = target->aimed_share;
  std::optional<Vec3> w;
  if (u_aim < share)
    w = cone->frame.to_world(sample_uniform_cone(u_dir, cone->cos_max));
  else
    w = own_sample(u_dir);
  if (!w) return std::nullopt;
  return MixedDirection{*w, share * cone->density(*w) + (1.f - share) * own_pdf(*w)};
}

// A ray travelling along `direction`, starting outside the scene's bounding
// sphere (radius r), through a point of the plane across the beam: uniform over
// the scene's disk or, with probability aimed_share, over the target's disk.
// `density` is the mixture's per unit area of that plane.
struct BeamRay {
  Ray ray;
  float density;
};
BeamRay beam_ray(const Vec3& direction, Point2 u, float u_aim, const GeometryScene& scene, float radius,
                 const EmissionTarget* target) {
  const Frame frame = Frame::from_z(direction);
  const Vec3 centre = scene.bounds().center();
  const float scene_density = 1.f / (kPi * radius * radius);
  const Point2 d = sample_uniform_disk_concentric(u);
  Point2 q{d.x * radius, d.y * radius};  // across the beam, from the scene's centre
  float density = scene_density;
  if (target && target->radius > 0.f) {
    const Vec3 offset = frame.to_local(target->centre - centre);
    const float R = target->radius;
    if (u_aim < target->aimed_share) q = Point2{offset.x + d.x * R, offset.y + d.y * R};
    const float dx = q.x - offset.x, dy = q.y - offset.y;
    const bool in_target = dx * dx + dy * dy <= R * R;
    const bool in_scene = q.x * q.x + q.y * q.y <= radius * radius;
    density = target->aimed_share * (in_target ? 1.f / (kPi * R * R) : 0.f) +
              (1.f - target->aimed_share) * (in_scene ? scene_density : 0.f);
  }
  return BeamRay{Ray{centre + frame.to_world(Vec3{q.x, q.y, -radius}), direction}, density};
}

// The directions a light at a point emits its own rays into: point lights
// uniformly over the sphere, spot lights uniformly within the outer cone.
float own_direction_pdf(const PointLight&, const Vec3&) { return uniform_sphere_pdf(); }
float own_direction_pdf(const SpotLight& light, const Vec3& w) {
  return dot(w, light.direction) >= light.cos_falloff_end ? uniform_cone_pdf(light.cos_falloff_end) : 0.f;
}

// Cosine-weighted about the normal n at the emitting point (each side with probability ½ if two-sided).
float own_direction_pdf(const AreaLight& light, const Vec3& n, const Vec3& w) {
  const float cos_n = dot(w, n);
  if (!light.two_sided && !(cos_n > 0.f)) return 0.f;
  return (light.two_sided ? 0.5f : 1.f) * std::fabs(cos_n) * kInvPi;
}

std::optional<LightEmission> emit(const PointLight& light, Point2, Point2 u_dir, float lambda, const GeometryScene&,
                                  const EmissionTarget* target, float u_aim) {
  const auto dir = mixed_direction(
      target, light.position, u_dir, u_aim, [](Point2 u) -> std::optional<Vec3> { return sample_uniform_sphere(u); },
      [&](const Vec3& w) { return own_direction_pdf(light, w); });
  if (!dir) return std::nullopt;
  const float flux = light.I(lambda) * light.scale / dir->pdf;
  if (!(flux > 0.f)) return std::nullopt;
  return LightEmission{Ray{light.position, dir->w}, flux, light.position, Vec3{}};
}

std::optional<LightEmission> emit(const SpotLight& light, Point2, Point2 u_dir, float lambda, const GeometryScene&,
                                  const EmissionTarget* target, float u_aim) {
  const Frame axis = Frame::from_z(light.direction);
  const auto dir = mixed_direction(
      target, light.position, u_dir, u_aim,
      [&](Point2 u) -> std::optional<Vec3> { return axis.to_world(sample_uniform_cone(u, light.cos_falloff_end)); },
      [&](const Vec3& w) { return own_direction_pdf(light, w); });
  if (!dir || !(dir->pdf > 0.f)) return std::nullopt;
  const float flux = light.I(lambda) * light.scale * spot_falloff(light, dir->w) / dir->pdf;
  if (!(flux > 0.f)) return std::nullopt;
  return LightEmission{Ray{light.position, dir->w}, flux, light.position, Vec3{}};
}

std::optional<LightEmission> emit(const AreaLight& light, Point2 u_pos, Point2 u_dir, float lambda,
                                  const GeometryScene& scene, const EmissionTarget* target, float u_aim) {
  const ShapeSample ss = scene.sample_area(light.shape_id, u_pos);
  const auto dir = mixed_direction(
      target, ss.p, u_dir, u_aim,
      [&](Point2 u) -> std::optional<Vec3> {
        Vec3 n = ss.n;
        if (light.two_sided) {
          if (u.x < 0.5f) {
            u.x *= 2.f;
          } else {
            u.x = (u.x - 0.5f) * 2.f;
            n = -n;
          }
        }
        const Vec3 local = sample_cosine_hemisphere(u);
        if (!(local.z > 0.f)) return std::nullopt;
        return Frame::from_z(n).to_world(local);
      },
      [&](const Vec3& w) { return own_direction_pdf(light, ss.n, w); });
  if (!dir || !(dir->pdf > 0.f)) return std::nullopt;
  const float cos_n = dot(dir->w, ss.n);
  if (!light.two_sided && !(cos_n > 0.f)) return std::nullopt;  // an aimed ray behind a one-sided emitter
  // Le |cosθ| / (pdf_area · pdf_direction).
  const float flux = light.Le(lambda) * light.scale * std::fabs(cos_n) / (ss.pdf_area * dir->pdf);
  if (!(flux > 0.f)) return std::nullopt;
  // Leave the surface as a hit on it would: offset by a bound on the sampled point's
  // rounding (a few ulps of its coordinates; interpolating corners).
  SurfaceHit on_light;
  on_light.p = ss.p;
  on_light.ng = on_light.ns = ss.n;
  on_light.shape_id = light.shape_id;
  on_light.p_error = 32.f * std::numeric_limits<float>::epsilon() * max_component(abs(ss.p));
  return LightEmission{scene.spawn_ray(on_light, dir->w), flux, ss.p, ss.n};
}

std::optional<LightEmission> emit(const DistantLight& light, Point2 u_pos, Point2, float lambda,
                                  const GeometryScene& scene, const EmissionTarget* target, float u_aim) {
  const BeamRay beam = beam_ray(light.direction, u_pos, u_aim, scene, light.scene_radius, target);
  if (!(beam.density > 0.f)) return std::nullopt;
  const float flux = light.L(lambda) * light.scale / beam.density;
  if (!(flux > 0.f)) return std::nullopt;
  return LightEmission{beam.ray, flux, Vec3{}, Vec3{}};
}

std::optional<LightEmission> emit(const EnvironmentLight& light, Point2 u_pos, Point2 u_dir, float lambda,
                                  const GeometryScene& scene, const EmissionTarget* target, float u_aim) {
  const Vec3 w = sample_uniform_sphere(u_dir);  // the way the light travels
  const BeamRay beam = beam_ray(w, u_pos, u_aim, scene, light.scene_radius, target);
  if (!(beam.density > 0.f)) return std::nullopt;
  const float flux = light.L(lambda) * light.scale / (beam.density * uniform_sphere_pdf());
  if (!(flux > 0.f)) return std::nullopt;
  return LightEmission{beam.ray, flux, Vec3{}, Vec3{}};
}

}  // namespace

std::optional<LightEmission> sample_emission(const Light& light, Point2 u_position, Point2 u_direction,
                                             float lambda_nm, const GeometryScene& scene,
                                             const EmissionTarget* target, float u_aim) {
  return std::visit(
      [&](const auto& l) { return emit(l, u_position, u_direction, lambda_nm, scene, target, u_aim); }, light);
}

float emission_area_direction_pdf(const AreaLight& light, const Vec3& n, const Vec3& w, const GeometryScene& scene) {
  return own_direction_pdf(light, n, w) / scene.area(light.shape_id);
}

float emission_direction_pdf(const Light& light, const Vec3& w) {
  if (const auto* point = std::get_if<PointLight>(&light)) return own_direction_pdf(*point, w);
  if (const auto* spot = std::get_if<SpotLight>(&light)) return own_direction_pdf(*spot, w);
  return 0.f;
}

}  // namespace chlorovdb
