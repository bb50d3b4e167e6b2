#include "camera/camera.h"

#include <cmath>
#include <stdexcept>

#include "core/constants.h"

namespace chlorovdb {

Camera::Camera(Projection projection, int width, int height)
    : projection_(std::move(projection)), width_(width), height_(height) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("camera resolution must be positive");
  const float aspect = float(width) / float(height);
  if (const auto* p = std::get_if<PerspectiveCamera>(&projection_)) {
    if (!(p->fov_degrees > 0.f && p->fov_degrees < 180.f)) throw std::invalid_argument("fov must be in (0, 180) degrees");
    if (!(p->lens_radius >= 0.f)) throw std::invalid_argument("lens radius must be >= 0");
    if (!(p->focus_distance > 0.f)) throw std::invalid_argument("focus distance must be > 0");
    const float half_short = std::tan(0.5f * p->fov_degrees * kPi / 180.f);
    half_width_ = aspect >= 1.f ? half_short * aspect : half_short;
    half_height_ = aspect >= 1.f ? half_short : half_short / aspect;
  } else {
    const auto& o = std::get<OrthographicCamera>(projection_);
    if (!(o.screen_height > 0.f)) throw std::invalid_argument("screen height must be > 0");
    half_height_ = 0.5f * o.screen_height;
    half_width_ = half_height_ * aspect;
  }
}

Ray Camera::generate_ray(Point2 film_pixel, Point2 u_lens) const {
  // Film to camera-space screen: image right is camera -x, image down is camera -y.
  const float sx = (1.f - 2.f * film_pixel.x / float(width_)) * half_width_;
  const float sy = (1.f - 2.f * film_pixel.y / float(height_)) * half_height_;
  if (const auto* p = std::get_if<PerspectiveCamera>(&projection_)) {
    Vec3 o{0, 0, 0}, d{sx, sy, 1.f};
    if (p->lens_radius > 0.f) {
      // Thin lens: every lens point's ray passes the pinhole ray's point on the focal plane.
      const Point2 lens = sample_uniform_disk_concentric(u_lens);
      o = Vec3(p->lens_radius * lens.x, p->lens_radius * lens.y, 0.f);
      d = d * p->focus_distance - o;
    }
    return {p->world_from_camera.point(o), normalize(p->world_from_camera.vector(d))};
  }
  const auto& ortho = std::get<OrthographicCamera>(projection_);
  return {ortho.world_from_camera.point({sx, sy, 0.f}), normalize(ortho.world_from_camera.vector({0, 0, 1}))};
}

std::optional<Point2> Camera::film_position(const Vec3& p_world) const {
  const bool perspective = std::holds_alternative<PerspectiveCamera>(projection_);
  const Transform& world_from_camera = perspective ? std::get<PerspectiveCamera>(projection_).world_from_camera
                                                   : std::get<OrthographicCamera>(projection_).world_from_camera;
  const Vec3 pc = world_from_camera.inverse().point(p_world);
  float sx = pc.x, sy = pc.y;
  if (perspective) {
    if (pc.z <= 0.f) return std::nullopt;
    sx /= pc.z;
    sy /= pc.z;
  }
  return Point2{0.5f * float(width_) * (1.f - sx / half_width_), 0.5f * float(height_) * (1.f - sy / half_height_)};
}

}  // namespace chlorovdb
