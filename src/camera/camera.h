#pragma once
// Cameras: perspective (pinhole or thin lens) and orthographic.
//
// Conventions. World space is right-handed. Camera space is the frame of
// Transform::look_at(eye, target, up): +z looks at the target, +y is `up`, and
// +x = cross(up, view): in a right-handed world that is the viewer's LEFT.
// Film pixels are continuous coordinates with (0, 0) at the top-left corner,
// x growing to the right and y downward, (width, height) at the bottom-right.
// So image right is camera -x (= cross(view, up), the viewer's right) and
// image up is camera +y: what the user sees from eye toward target has `up`
// up and right on the right.
#include <optional>
#include <variant>

#include "core/sampling.h"
#include "core/transform.h"
#include "core/vec.h"

namespace chlorovdb {

struct PerspectiveCamera {
  Transform world_from_camera;
  float fov_degrees;           // full field of view across the SHORTER image side
  float lens_radius = 0.f;     // metres; 0 is a pinhole
  float focus_distance = 1.f;  // metres along the view axis to the plane in focus (thin lens only)
};

struct OrthographicCamera {
  Transform world_from_camera;
  float screen_height;  // metres covered by the image height
};

class Camera {
 public:
  using Projection = std::variant<PerspectiveCamera, OrthographicCamera>;
  // Throws std::invalid_argument for a non-positive resolution, fov outside
  // (0, 180), negative lens radius, non-positive focus distance or screen height.
  Camera(Projection projection, int width, int height);

  // World-space ray with unit direction through the continuous pixel position
  // film_pixel; u_lens in [0,1)² picks the point on the lens (ignored by a pinhole
  // or orthographic camera).
  Ray generate_ray(Point2 film_pixel, Point2 u_lens) const;
  // Where a world point lands on the film (through the lens centre); nullopt if
  // it is behind a perspective camera.
  std::optional<Point2> film_position(const Vec3& p_world) const;

  int width() const { return width_; }
  int height() const { return height_; }
  const Projection& projection() const { return projection_; }

 private:
  Projection projection_;
  int width_, height_;
  // Half extent of the image on the camera's z = 1 plane (perspective) or in metres (orthographic).
  float half_width_, half_height_;
};

}  // namespace chlorovdb
