// Self-intersection robustness: spawned rays must not re-hit the surface they
// leave, including far from the world origin where float spacing is ~1 cm.
#include <gtest/gtest.h>

#include <cmath>

#include "core/constants.h"
#include "core/rng.h"
#include "geometry/geometry_scene.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

namespace {

// Direction at `elevation` radians above (sign +1) or below (-1) the tangent plane of n.
Vec3 grazing_direction(const Vec3& n, float elevation, float azimuth, float side) {
  const Frame f = Frame::from_z(n);
  const float c = std::cos(elevation), s = std::sin(elevation);
  return normalize(f.to_world({c * std::cos(azimuth), c * std::sin(azimuth), side * s}));
}

struct Counts {
  int hits = 0, self_hits = 0;
};

// Hits the shape from `eye` toward points near `target`, then spawns grazing
// rays away from the surface on both sides. For a plane or a convex shape, a
// ray leaving on the outer side can never hit it again; a ray into a convex
// solid must reach the far side (t well above zero).
Counts probe(const GeometryScene& scene, int shape, Vec3 eye, Vec3 target, float jitter, bool convex_solid,
             float min_inner_t) {
  Counts counts;
  Rng rng(test_seed(17), 0);
  for (int i = 0; i < 4000; ++i) {
    const Vec3 aim = target + jitter * Vec3(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f);
    const auto hit = scene.intersect({eye, normalize(aim - eye)}, kInfinity);
    if (!hit || hit->shape_id != shape) continue;
    ++counts.hits;
    const float elevation = std::pow(10.f, -3.f + 2.f * rng.uniform());  // 1e-3 .. 1e-1 rad
    const float azimuth = 2.f * kPi * rng.uniform();
    const Vec3 out = grazing_direction(hit->ng, elevation, azimuth, +1.f);
    const auto again = scene.intersect(scene.spawn_ray(*hit, out), kInfinity);
    if (again && again->shape_id == shape) ++counts.self_hits;
    const Vec3 in = grazing_direction(hit->ng, elevation, azimuth, -1.f);
    const auto inner = scene.intersect(scene.spawn_ray(*hit, in), kInfinity);
    if (convex_solid) {
      if (!inner || inner->shape_id != shape || inner->t < min_inner_t) ++counts.self_hits;
    } else if (inner && inner->shape_id == shape) {
      ++counts.self_hits;
    }
  }
  return counts;
}

}  // namespace

TEST(SpawnRay, FarFromOriginTiltedQuad) {
  const Vec3 center{1e5f, -3e4f, 1e5f};
  GeometryScene scene;
  const Transform world_from_object =
      Transform::translate(center) * Transform::rotate(37.f, {1, 2, 3}) * Transform::translate({-5, -5, 0});
  const int quad = scene.add_mesh(make_quad({0, 0, 0}, {10, 0, 0}, {0, 10, 0}), world_from_object);
  scene.commit();
  const Vec3 n = normalize(world_from_object.normal({0, 0, 1}));
  const Counts c = probe(scene, quad, center + 50.f * n, center, 8.f, false, 0.f);
  EXPECT_GT(c.hits, 1000);
  EXPECT_EQ(c.self_hits, 0);
}

TEST(SpawnRay, HugeGroundQuadAroundTheOrigin) {
  // Vertices at 1e5 m: the interpolation error at a hit near the origin is set
  // by the vertices, not by the hit point.
  GeometryScene scene;
  const int ground = scene.add_mesh(make_quad({-1e5f, -1e5f, 0}, {2e5f, 0, 0}, {0, 2e5f, 0}));
  scene.commit();
  const Counts c = probe(scene, ground, {3, 4, 20}, {0, 0, 0}, 10.f, false, 0.f);
  EXPECT_GT(c.hits, 1000);
  EXPECT_EQ(c.self_hits, 0);
}

TEST(SpawnRay, FarFromOriginAnalyticSphere) {
  const Vec3 center{-1e5f, 1e5f, 2e4f};
  GeometryScene scene;
  const int sphere = scene.add_sphere(center, 2.f);
  scene.commit();
  // Inner grazing rays (elevation >= 1e-3) travel a chord of at least 2 r sin(1e-3) = 4 mm.
  const Counts c = probe(scene, sphere, center + Vec3(30, 20, -10), center, 3.f, true, 2e-3f);
  EXPECT_GT(c.hits, 1000);
  EXPECT_EQ(c.self_hits, 0);
}

TEST(SpawnRay, FarFromOriginMeshSphere) {
  const Vec3 center{1e5f, 1e5f, -1e5f};
  GeometryScene scene;
  const int sphere = scene.add_mesh(make_uv_sphere({0, 0, 0}, 2.f, 32, 64), Transform::translate(center));
  scene.commit();
  // Each flat facet is locally a plane: outward rays must miss the mesh; the
  // chord bound for inward rays does not hold near facet edges, so only t > 0.
  const Counts c = probe(scene, sphere, center + Vec3(-20, 30, 10), center, 3.f, true, 0.f);
  EXPECT_GT(c.hits, 1000);
  EXPECT_EQ(c.self_hits, 0);
}

TEST(SpawnRay, ShadowRayToALightSurfaceIsNotBlockedByIt) {
  const Vec3 offset{1e5f, 0, 1e5f};
  GeometryScene scene;
  scene.add_mesh(make_quad({-10, -10, 0}, {20, 0, 0}, {0, 20, 0}), Transform::translate(offset));
  const int light = scene.add_mesh(make_quad({-1, -1, 0}, {0, 2, 0}, {2, 0, 0}), Transform::translate(offset + Vec3(0, 0, 3)));
  scene.commit();
  Rng rng(test_seed(23), 0);
  int blocked = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 aim = offset + Vec3(16 * rng.uniform() - 8, 16 * rng.uniform() - 8, 0);
    const auto floor = scene.intersect({aim + Vec3(0.1f, 0.2f, 1), normalize(Vec3(-0.1f, -0.2f, -1))}, kInfinity);
    ASSERT_TRUE(floor);
    const ShapeSample s = scene.sample_area(light, {rng.uniform(), rng.uniform()});
    float t_max;
    const Ray r = scene.spawn_ray_to(*floor, s.p, &t_max);
    EXPECT_NEAR(length(r.d), 1.f, 1e-6f);
    // Float spacing at 1e5 m is 7.8 mm: the shadow ray may stop a few spacings short, no more.
    EXPECT_LT(t_max, distance(floor->p, s.p));
    EXPECT_GT(t_max, distance(floor->p, s.p) - 0.1f);
    if (scene.occluded(r, t_max)) ++blocked;
  }
  EXPECT_EQ(blocked, 0);
}

TEST(SpawnRay, ShadowRayNearTheOriginStopsJustShort) {
  GeometryScene scene;
  scene.add_mesh(make_quad({-1, -1, 0}, {2, 0, 0}, {0, 2, 0}));
  scene.commit();
  const auto hit = scene.intersect({{0.2f, 0.1f, 1}, {0, 0, -1}}, kInfinity);
  ASSERT_TRUE(hit);
  float t_max;
  const Ray r = scene.spawn_ray_to(*hit, {0.2f, 0.1f, 2}, &t_max);
  EXPECT_NEAR(t_max, 2.f, 1e-3f);
  EXPECT_GT(r.o.z, 0.f);
  EXPECT_LT(r.o.z, 1e-6f);
}
