#include <gtest/gtest.h>

#include <cmath>

#include "camera/camera.h"
#include "core/constants.h"
#include "core/rng.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

namespace {

const Vec3 kEye{1, 2, 3}, kTarget{4, -1, 7}, kUp{0, 1, 0};

float angle_degrees(Vec3 a, Vec3 b) {
  return std::acos(std::clamp(dot(normalize(a), normalize(b)), -1.f, 1.f)) * 180.f / kPi;
}

float distance_to_line(const Ray& r, Vec3 p) {
  const Vec3 d = normalize(r.d);
  const Vec3 v = p - r.o;
  return length(v - d * dot(v, d));
}

void expect_near(Vec3 a, Vec3 b, float tol) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

}  // namespace

TEST(Camera, CenterRayHitsTheLookAtTarget) {
  const Camera cam(PerspectiveCamera{Transform::look_at(kEye, kTarget, kUp), 45.f}, 320, 240);
  const Ray r = cam.generate_ray({160, 120}, {0.5f, 0.5f});
  expect_near(r.o, kEye, 1e-5f);
  EXPECT_NEAR(length(r.d), 1.f, 1e-6f);
  EXPECT_LT(distance_to_line(r, kTarget), 1e-4f);
  EXPECT_GT(dot(r.d, kTarget - kEye), 0.f);
}

TEST(Camera, FovSpansTheShorterSide) {
  const Transform wfc = Transform::look_at(kEye, kTarget, kUp);
  const Vec3 view = normalize(kTarget - kEye);
  const float half_tan = std::tan(30.f * kPi / 180.f);
  // Landscape: the fov is vertical.
  const Camera landscape(PerspectiveCamera{wfc, 60.f}, 400, 200);
  EXPECT_NEAR(angle_degrees(landscape.generate_ray({200, 0}, {}).d, view), 30.f, 1e-3f);
  EXPECT_NEAR(angle_degrees(landscape.generate_ray({200, 200}, {}).d, view), 30.f, 1e-3f);
  EXPECT_NEAR(angle_degrees(landscape.generate_ray({0, 100}, {}).d, view),
              std::atan(2.f * half_tan) * 180.f / kPi, 1e-3f);
  // Portrait: the fov is horizontal.
  const Camera portrait(PerspectiveCamera{wfc, 60.f}, 200, 400);
  EXPECT_NEAR(angle_degrees(portrait.generate_ray({0, 200}, {}).d, view), 30.f, 1e-3f);
  EXPECT_NEAR(angle_degrees(portrait.generate_ray({100, 0}, {}).d, view),
              std::atan(2.f * half_tan) * 180.f / kPi, 1e-3f);
}

TEST(Camera, RightIsRightAndUpIsUpInARightHandedWorld) {
  // Looking from +z toward the origin with +y up, a right-handed viewer has +x on the right.
  const Camera simple(PerspectiveCamera{Transform::look_at({0, 0, 5}, {0, 0, 0}, {0, 1, 0}), 50.f}, 100, 80);
  EXPECT_GT(simple.generate_ray({90, 40}, {}).d.x, 0.f);
  EXPECT_GT(simple.generate_ray({50, 5}, {}).d.y, 0.f);

  const Camera cam(PerspectiveCamera{Transform::look_at(kEye, kTarget, kUp), 50.f}, 100, 80);
  const Vec3 view = normalize(kTarget - kEye), right = normalize(cross(view, kUp)),
             up = normalize(cross(right, view));
  const auto p_right = cam.film_position(kTarget + 0.5f * right);
  ASSERT_TRUE(p_right);
  EXPECT_GT(p_right->x, 50.f);
  EXPECT_NEAR(p_right->y, 40.f, 1e-3f);
  const auto p_up = cam.film_position(kTarget + 0.5f * up);
  ASSERT_TRUE(p_up);
  EXPECT_LT(p_up->y, 40.f);
  EXPECT_NEAR(p_up->x, 50.f, 1e-3f);
  EXPECT_FALSE(cam.film_position(kEye - view));
}

TEST(Camera, FilmPositionInvertsGenerateRay) {
  const Camera cam(PerspectiveCamera{Transform::look_at(kEye, kTarget, kUp), 70.f}, 640, 360);
  Rng rng(test_seed(1), 0);
  for (int i = 0; i < 100; ++i) {
    const Point2 px{640 * rng.uniform(), 360 * rng.uniform()};
    const auto back = cam.film_position(cam.generate_ray(px, {}).at(3.7f));
    ASSERT_TRUE(back);
    EXPECT_NEAR(back->x, px.x, 2e-3f);
    EXPECT_NEAR(back->y, px.y, 2e-3f);
  }
}

TEST(Camera, ThinLensRaysConvergeAtTheFocusDistance) {
  const float focus = 6.f;
  const Vec3 view = normalize(kTarget - kEye);
  const Camera cam(PerspectiveCamera{Transform::look_at(kEye, kTarget, kUp), 40.f, 0.1f, focus}, 300, 200);
  const Camera pinhole(PerspectiveCamera{Transform::look_at(kEye, kTarget, kUp), 40.f}, 300, 200);
  Rng rng(test_seed(2), 0);
  for (const Point2 px : {Point2{150, 100}, Point2{20, 30}, Point2{290, 180}}) {
    const Ray p = pinhole.generate_ray(px, {});
    const Vec3 in_focus = p.at(focus / dot(p.d, view));  // on the plane at depth `focus`
    float max_offset = 0.f;
    for (int i = 0; i < 200; ++i) {
      const Ray r = cam.generate_ray(px, {rng.uniform(), rng.uniform()});
      EXPECT_NEAR(length(r.d), 1.f, 1e-6f);
      EXPECT_NEAR(dot(r.o - kEye, view), 0.f, 1e-5f) << "lens lies in the plane through the eye";
      EXPECT_LE(distance(r.o, kEye), 0.1f + 1e-5f);
      max_offset = std::max(max_offset, distance(r.o, kEye));
      const Vec3 q = r.at((focus - dot(r.o - kEye, view)) / dot(r.d, view));
      EXPECT_LT(distance(q, in_focus), 1e-4f);
    }
    EXPECT_GT(max_offset, 0.05f) << "lens samples must spread over the aperture";
  }
}

TEST(Camera, OrthographicRaysAreParallel) {
  const Vec3 view = normalize(kTarget - kEye);
  const Camera cam(OrthographicCamera{Transform::look_at(kEye, kTarget, kUp), 2.f}, 200, 100);
  const Ray center = cam.generate_ray({100, 50}, {0.3f, 0.9f});
  expect_near(center.o, kEye, 1e-5f);
  Rng rng(test_seed(3), 0);
  for (int i = 0; i < 50; ++i) {
    const Ray r = cam.generate_ray({200 * rng.uniform(), 100 * rng.uniform()}, {rng.uniform(), rng.uniform()});
    expect_near(r.d, view, 1e-6f);
    EXPECT_NEAR(dot(r.o - kEye, view), 0.f, 1e-5f);
  }
  // The image is 2 m high and 4 m wide; right is right.
  const Vec3 right = normalize(cross(view, kUp));
  const Ray left_edge = cam.generate_ray({0, 50}, {}), right_edge = cam.generate_ray({200, 50}, {});
  EXPECT_NEAR(dot(right_edge.o - left_edge.o, right), 4.f, 1e-5f);
  const Ray top = cam.generate_ray({100, 0}, {}), bottom = cam.generate_ray({100, 100}, {});
  EXPECT_NEAR(distance(top.o, bottom.o), 2.f, 1e-5f);
  EXPECT_GT(dot(top.o - bottom.o, kUp), 0.f);
  const auto back = cam.film_position(kEye + right + 3.f * view);
  ASSERT_TRUE(back);
  EXPECT_NEAR(back->x, 150.f, 1e-3f);
}

TEST(Camera, InvalidParametersAreRejected) {
  const Transform t = Transform::look_at(kEye, kTarget, kUp);
  EXPECT_THROW(Camera(PerspectiveCamera{t, 0.f}, 10, 10), std::invalid_argument);
  EXPECT_THROW(Camera(PerspectiveCamera{t, 180.f}, 10, 10), std::invalid_argument);
  EXPECT_THROW(Camera(PerspectiveCamera{t, 45.f, -1.f}, 10, 10), std::invalid_argument);
  EXPECT_THROW(Camera(PerspectiveCamera{t, 45.f}, 0, 10), std::invalid_argument);
  EXPECT_THROW(Camera(OrthographicCamera{t, 0.f}, 10, 10), std::invalid_argument);
}
