#include "lights/light_emission.h"

#include <cmath>
#include <limits>

#include "core/sampling.h"

namespace chlorovdb {

namespace {

// A ray travelling along `direction` through a disk of radius r around the
// scene's centre, starting outside its bounding sphere: density 1 / (π r²) over the disk.
Ray ray_through_scene_disk(const Vec3& direction, Point2 u, const GeometryScene& scene, float radius) {
  const Frame frame = Frame::from_z(direction);
  const Point2 d = sample_uniform_disk_concentric(u);
  const Vec3 centre = scene.bounds().center();
  return Ray{centre + frame.to_world(Vec3{d.x * radius, d.y * radius, -radius}), direction};
}

std::optional<LightEmission> emit(const PointLight& light, Point2, Point2 u_dir, float lambda, const GeometryScene&) {
  const float flux = light.I(lambda) * light.scale / uniform_sphere_pdf();
  if (!(flux > 0.f)) return std::nullopt;
  return LightEmission{Ray{light.position, sample_uniform_sphere(u_dir)}, flux};
}

std::optional<LightEmission> emit(const SpotLight& light, Point2, Point2 u_dir, float lambda, const GeometryScene&) {
  const Vec3 w = Frame::from_z(light.direction).to_world(sample_uniform_cone(u_dir, light.cos_falloff_end));
  const float flux = light.I(lambda) * light.scale * spot_falloff(light, w) / uniform_cone_pdf(light.cos_falloff_end);
  if (!(flux > 0.f)) return std::nullopt;
  return LightEmission{Ray{light.position, w}, flux};
}

std::optional<LightEmission> emit(const AreaLight& light, Point2 u_pos, Point2 u_dir, float lambda,
                                  const GeometryScene& scene) {
  const ShapeSample ss = scene.sample_area(light.shape_id, u_pos);
  Vec3 n = ss.n;
  float side_pdf = 1.f;
  if (light.two_sided) {
    side_pdf = 0.5f;
    if (u_dir.x < 0.5f) {
      u_dir.x *= 2.f;
    } else {
      u_dir.x = (u_dir.x - 0.5f) * 2.f;
      n = -n;
    }
  }
  const Vec3 local = sample_cosine_hemisphere(u_dir);
  if (!(local.z > 0.f)) return std::nullopt;
  // Le cosθ / (pdf_area · cosθ/π · side_pdf): the cosine cancels.
  const float flux = light.Le(lambda) * light.scale * kPi / (ss.pdf_area * side_pdf);
  if (!(flux > 0.f)) return std::nullopt;
  const Vec3 w = Frame::from_z(n).to_world(local);
  // Leave the surface as a hit on it would: offset by a bound on the sampled point's
  // rounding (a few ulps of its coordinates; interpolating corners).
  SurfaceHit on_light;
  on_light.p = ss.p;
  on_light.ng = on_light.ns = ss.n;
  on_light.shape_id = light.shape_id;
  on_light.p_error = 32.f * std::numeric_limits<float>::epsilon() * max_component(abs(ss.p));
  return LightEmission{scene.spawn_ray(on_light, w), flux};
}

std::optional<LightEmission> emit(const DistantLight& light, Point2 u_pos, Point2, float lambda,
                                  const GeometryScene& scene) {
  const float r = light.scene_radius;
  const float flux = light.L(lambda) * light.scale * kPi * r * r;
  if (!(flux > 0.f)) return std::nullopt;
  return LightEmission{ray_through_scene_disk(light.direction, u_pos, scene, r), flux};
}

std::optional<LightEmission> emit(const EnvironmentLight& light, Point2 u_pos, Point2 u_dir, float lambda,
                                  const GeometryScene& scene) {
  const float r = light.scene_radius;
  const Vec3 w = sample_uniform_sphere(u_dir);  // the way the light travels
  const float flux = light.L(lambda) * light.scale * kPi * r * r / uniform_sphere_pdf();
  if (!(flux > 0.f)) return std::nullopt;
  return LightEmission{ray_through_scene_disk(w, u_pos, scene, r), flux};
}

}  // namespace

std::optional<LightEmission> sample_emission(const Light& light, Point2 u_position, Point2 u_direction,
                                             float lambda_nm, const GeometryScene& scene) {
  return std::visit([&](const auto& l) { return emit(l, u_position, u_direction, lambda_nm, scene); }, light);
}

}  // namespace chlorovdb
