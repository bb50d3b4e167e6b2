#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cmath>
#include <thread>

#include "core/constants.h"
#include "core/rng.h"
#include "geometry/geometry_scene.h"
#include "test_seed.h"

using namespace chlorovdb;
using chlorovdb::test::test_seed;

namespace {

void expect_near(const Vec3& a, const Vec3& b, float tol) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

}  // namespace

TEST(GeometryScene, ShapeIdsAreDenseInInsertionOrder) {
  GeometryScene scene;
  EXPECT_EQ(scene.add_mesh(make_quad({-1, -1, 0}, {2, 0, 0}, {0, 2, 0})), 0);
  EXPECT_EQ(scene.add_sphere({0, 0, 5}, 1.f), 1);
  EXPECT_EQ(scene.add_mesh(make_box({{3, 3, 3}, {4, 4, 4}})), 2);
  scene.commit();
  EXPECT_EQ(scene.shape_count(), 3);
  EXPECT_EQ(scene.intersect({{0, 0, -3}, {0, 0, 1}}, kInfinity)->shape_id, 0);
  EXPECT_EQ(scene.intersect({{0, 0, 1}, {0, 0, 1}}, kInfinity)->shape_id, 1);
  EXPECT_EQ(scene.intersect({{3.5f, 3.5f, 0}, {0, 0, 1}}, kInfinity)->shape_id, 2);
  const Bounds3 b = scene.bounds();
  expect_near(b.lo, {-1, -1, 0}, 0);
  expect_near(b.hi, {4, 4, 6}, 0);
}

TEST(GeometryScene, QuadHitAtKnownDistance) {
  GeometryScene scene;
  scene.add_mesh(make_quad({-1, -1, 0}, {2, 0, 0}, {0, 2, 0}), Transform::translate({0, 0, 2}));
  scene.commit();
  const auto hit = scene.intersect({{0.25f, -0.5f, 7}, {0, 0, -1}}, kInfinity);
  ASSERT_TRUE(hit);
  EXPECT_FLOAT_EQ(hit->t, 5.f);
  expect_near(hit->p, {0.25f, -0.5f, 2}, 1e-6f);
  EXPECT_EQ(hit->ng, Vec3(0, 0, 1));
  EXPECT_EQ(hit->ns, Vec3(0, 0, 1));
  EXPECT_NEAR(hit->uv.x, 0.625f, 1e-6f);
  EXPECT_NEAR(hit->uv.y, 0.25f, 1e-6f);
  // From below: the normal stays as stored (not flipped toward the ray).
  const auto below = scene.intersect({{0, 0, -1}, {0, 0, 1}}, kInfinity);
  ASSERT_TRUE(below);
  EXPECT_FLOAT_EQ(below->t, 3.f);
  EXPECT_EQ(below->ng, Vec3(0, 0, 1));
  EXPECT_FALSE(scene.intersect({{1.5f, 0, 7}, {0, 0, -1}}, kInfinity));
  EXPECT_FALSE(scene.intersect({{0, 0, 7}, {0, 0, -1}}, 4.9f)) << "t_max must bound the search";
}

TEST(GeometryScene, BoxEnteringAndLeaving) {
  GeometryScene scene;
  scene.add_mesh(make_box({{-1, -1, -1}, {1, 1, 1}}));
  scene.commit();
  const Ray outside{{-5, 0.1f, 0.2f}, {1, 0, 0}};
  const auto enter = scene.intersect(outside, kInfinity);
  ASSERT_TRUE(enter);
  EXPECT_FLOAT_EQ(enter->t, 4.f);
  EXPECT_EQ(enter->ng, Vec3(-1, 0, 0));
  EXPECT_LT(dot(outside.d, enter->ng), 0.f);
  // Inside a closed mesh every ray sees ng along its direction (it is leaving).
  Rng rng(test_seed(7), 0);
  for (int i = 0; i < 200; ++i) {
    const Vec3 d = sample_uniform_sphere({rng.uniform(), rng.uniform()});
    const auto leave = scene.intersect({{0.1f, -0.2f, 0.3f}, d}, kInfinity);
    ASSERT_TRUE(leave);
    EXPECT_GT(dot(d, leave->ng), 0.f);
    EXPECT_NEAR(max_component(abs(leave->p)), 1.f, 1e-6f);
  }
}

TEST(GeometryScene, AnalyticSphereHits) {
  GeometryScene scene;
  const Vec3 c{1, 2, 3};
  scene.add_sphere(c, 2.f);
  scene.commit();
  const auto hit = scene.intersect({{1, 2, -10}, {0, 0, 1}}, kInfinity);
  ASSERT_TRUE(hit);
  EXPECT_FLOAT_EQ(hit->t, 11.f);
  expect_near(hit->p, {1, 2, 1}, 1e-6f);
  expect_near(hit->ng, {0, 0, -1}, 1e-6f);
  EXPECT_NEAR(hit->uv.y, 1.f, 1e-3f);  // theta = pi at -z
  // Non-unit direction: t is in units of the direction's length.
  const auto scaled = scene.intersect({{1, 2, -10}, {0, 0, 2}}, kInfinity);
  ASSERT_TRUE(scaled);
  EXPECT_FLOAT_EQ(scaled->t, 5.5f);
  // Tangent-ish miss and far miss.
  EXPECT_FALSE(scene.intersect({{3.01f, 2, -10}, {0, 0, 1}}, kInfinity));
  Rng rng(test_seed(3), 0);
  for (int i = 0; i < 200; ++i) {
    const Vec3 d = sample_uniform_sphere({rng.uniform(), rng.uniform()});
    const auto leave = scene.intersect({c + Vec3(0.3f, -0.1f, 0.5f), d}, kInfinity);
    ASSERT_TRUE(leave);
    EXPECT_GT(dot(d, leave->ng), 0.f);
    EXPECT_NEAR(distance(leave->p, c), 2.f, 1e-5f);
  }
}

TEST(GeometryScene, UvSphereMeshSeenFromInsideIsLeaving) {
  GeometryScene scene;
  scene.add_mesh(make_uv_sphere({0, 0, 0}, 1.f, 24, 48));
  scene.commit();
  Rng rng(test_seed(11), 0);
  for (int i = 0; i < 500; ++i) {
    const Vec3 d = sample_uniform_sphere({rng.uniform(), rng.uniform()});
    const auto hit = scene.intersect({{0, 0, 0}, d}, kInfinity);
    ASSERT_TRUE(hit) << "watertight mesh leaked a ray";
    EXPECT_GT(dot(d, hit->ng), 0.f);
    EXPECT_GT(dot(hit->ns, hit->ng), 0.f);
    EXPECT_NEAR(length(hit->ns), 1.f, 1e-5f);
  }
}

TEST(GeometryScene, DiskHitAndRim) {
  GeometryScene scene;
  scene.add_mesh(make_disk({0, 0, 2}, {0, 0, 1}, 1.f, 128));
  scene.commit();
  const auto hit = scene.intersect({{0.3f, 0.2f, 5}, {0, 0, -1}}, kInfinity);
  ASSERT_TRUE(hit);
  EXPECT_FLOAT_EQ(hit->t, 3.f);
  EXPECT_EQ(hit->ng, Vec3(0, 0, 1));
  EXPECT_TRUE(scene.intersect({{0.99f, 0, 5}, {0, 0, -1}}, kInfinity));
  EXPECT_FALSE(scene.intersect({{1.01f, 0, 5}, {0, 0, -1}}, kInfinity));
}

TEST(GeometryScene, Occlusion) {
  GeometryScene scene;
  scene.add_mesh(make_box({{-1, -1, -1}, {1, 1, 1}}));
  scene.add_sphere({0, 0, 10}, 1.f);
  scene.commit();
  EXPECT_FALSE(scene.occluded({{-5, 0, 0}, {1, 0, 0}}, 3.9f));
  EXPECT_TRUE(scene.occluded({{-5, 0, 0}, {1, 0, 0}}, 4.1f));
  EXPECT_FALSE(scene.occluded({{0, 0, 5}, {0, 0, 1}}, 3.9f));
  EXPECT_TRUE(scene.occluded({{0, 0, 5}, {0, 0, 1}}, 4.1f));
}

TEST(GeometryScene, SampleAreaIsUniformOnTheSurface) {
  GeometryScene scene;
  const int box = scene.add_mesh(make_box({{0, 0, 0}, {2, 1, 1}}));
  const int sphere = scene.add_sphere({5, 5, 5}, 0.5f);
  scene.commit();
  EXPECT_FLOAT_EQ(scene.area(box), 10.f);
  EXPECT_FLOAT_EQ(scene.area(sphere), kPi);

  // Box faces -x,+x have area 1, the four others 2: chi-square over the six faces.
  std::array<int, 6> counts{};
  const int n = 100000;
  Rng rng(test_seed(5), 0);
  for (int i = 0; i < n; ++i) {
    const ShapeSample s = scene.sample_area(box, {rng.uniform(), rng.uniform()});
    EXPECT_FLOAT_EQ(s.pdf_area, 0.1f);
    int face = -1;
    if (s.n.x != 0) face = s.n.x < 0 ? 0 : 1;
    if (s.n.y != 0) face = s.n.y < 0 ? 2 : 3;
    if (s.n.z != 0) face = s.n.z < 0 ? 4 : 5;
    ASSERT_GE(face, 0);
    const float coord = s.p[face / 2], expected = s.n[face / 2] < 0 ? 0.f : (face / 2 == 0 ? 2.f : 1.f);
    EXPECT_NEAR(coord, expected, 1e-6f) << "sample is not on its face";
    ++counts[face];
  }
  const std::array<float, 6> expected_fraction{0.1f, 0.1f, 0.2f, 0.2f, 0.2f, 0.2f};
  double chi2 = 0;
  for (int f = 0; f < 6; ++f) {
    const double e = n * expected_fraction[f];
    chi2 += (counts[f] - e) * (counts[f] - e) / e;
  }
  EXPECT_LT(chi2, 20.5) << "chi-square, 5 dof, p = 0.001";

  // Sphere: on the surface, outward normal, and z uniform in [-r, r] (Archimedes).
  double z_mean = 0, z2_mean = 0;
  for (int i = 0; i < n; ++i) {
    const ShapeSample s = scene.sample_area(sphere, {rng.uniform(), rng.uniform()});
    EXPECT_NEAR(distance(s.p, {5, 5, 5}), 0.5f, 1e-5f);
    expect_near(s.n, (s.p - Vec3(5, 5, 5)) / 0.5f, 1e-4f);
    EXPECT_FLOAT_EQ(s.pdf_area, 1.f / kPi);
    const double z = (s.p.z - 5.f) / 0.5f;
    z_mean += z / n;
    z2_mean += z * z / n;
  }
  EXPECT_NEAR(z_mean, 0.0, 0.01);
  EXPECT_NEAR(z2_mean, 1.0 / 3.0, 0.01);
}

TEST(GeometryScene, ConcurrentIntersectionsAgree) {
  GeometryScene scene;
  scene.add_mesh(make_uv_sphere({0, 0, 0}, 1.f, 16, 32));
  scene.add_sphere({3, 0, 0}, 1.f);
  scene.commit();
  std::atomic<int> mismatches{0};
  auto worker = [&](uint64_t stream) {
    Rng rng(test_seed(stream), 0);
    for (int i = 0; i < 20000; ++i) {
      const Vec3 d = sample_uniform_sphere({rng.uniform(), rng.uniform()});
      const Ray r{{1.5f, 0, 0}, d};
      const auto hit = scene.intersect(r, kInfinity);
      if (bool(hit) != scene.occluded(r, kInfinity)) ++mismatches;
    }
  };
  std::thread a(worker, 1), b(worker, 2);
  a.join();
  b.join();
  EXPECT_EQ(mismatches.load(), 0);
}

TEST(GeometryScene, MoveKeepsTheScene) {
  GeometryScene a;
  a.add_sphere({0, 0, 0}, 1.f);
  a.commit();
  GeometryScene b(std::move(a));
  EXPECT_TRUE(b.intersect({{0, 0, -5}, {0, 0, 1}}, kInfinity));
  GeometryScene c;
  c = std::move(b);
  EXPECT_TRUE(c.intersect({{0, 0, -5}, {0, 0, 1}}, kInfinity));
}

TEST(GeometryScene, AnalyticBoxAgreesWithTheBoxMesh) {
  // add_box (a slab test outside Embree) against make_box's triangles in Embree: the
  // same hits, faces, normals and occlusion, from inside and outside, axis-parallel
  // rays and rays bounded by t_max included.
  const Bounds3 box{{-1.f, -0.5f, 0.25f}, {2.f, 0.5f, 1.75f}};
  GeometryScene analytic, mesh;
  EXPECT_EQ(analytic.add_sphere({10, 10, 10}, 0.5f), 0);  // shares the id space with other shapes
  EXPECT_EQ(analytic.add_box(box), 1);
  analytic.commit();
  mesh.add_sphere({10, 10, 10}, 0.5f);
  mesh.add_mesh(make_box(box));
  mesh.commit();
  expect_near(analytic.bounds().lo, {-1.f, -0.5f, 0.25f}, 0);
  EXPECT_NEAR(analytic.area(1), 2.f * (3.f * 1.f + 1.f * 1.5f + 1.5f * 3.f), 1e-5f);
  Rng rng(test_seed(11), 0);
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    Vec3 o;
    for (int a = 0; a < 3; ++a) o[a] = box.lo[a] - 1.f + (box.diagonal()[a] + 2.f) * rng.uniform();
    Vec3 d = sample_uniform_sphere({rng.uniform(), rng.uniform()});
    if (i % 7 == 0) {
      d = Vec3(0.f);
      d[i % 3] = rng.uniform() < 0.5f ? -1.f : 1.f;
    }
    const float t_max = i % 3 == 0 ? 3.f * rng.uniform() : kInfinity;
    const Ray ray{o, d};
    const auto a = analytic.intersect(ray, t_max), m = mesh.intersect(ray, t_max);
    ASSERT_EQ(bool(a), bool(m)) << "ray " << i;
    EXPECT_EQ(analytic.occluded(ray, t_max), bool(m));
    if (!a) continue;
    EXPECT_EQ(a->shape_id, m->shape_id);
    if (a->shape_id != 1) continue;
    ++hits;
    EXPECT_NEAR(a->t, m->t, 1e-5f * (1.f + m->t));
    EXPECT_EQ(a->ng, m->ng);
    EXPECT_EQ(a->ns, a->ng);
    expect_near(a->p, m->p, 1e-5f);
    const int axis = a->prim_id / 2;
    EXPECT_EQ(a->p[axis], a->prim_id % 2 ? box.hi[axis] : box.lo[axis]) << "exactly on the face";
    EXPECT_GE(a->uv.x, 0.f);
    EXPECT_LE(a->uv.x, 1.f);
    // A ray spawned off the hit, either way, does not find the same face again.
    for (const Vec3& w : {d, -d}) {
      const auto next = analytic.intersect(analytic.spawn_ray(*a, w), kInfinity);
      if (next) EXPECT_FALSE(next->prim_id == a->prim_id && next->t < 1e-3f) << "re-hit, ray " << i;
    }
  }
  EXPECT_GT(hits, 3000);
}

TEST(GeometryScene, AnalyticBoxAreaSamplesAreUniform) {
  const Bounds3 box{{0.f, 0.f, 0.f}, {1.f, 2.f, 4.f}};
  GeometryScene scene;
  const int id = scene.add_box(box);
  scene.commit();
  const float area = scene.area(id);
  EXPECT_FLOAT_EQ(area, 2.f * (2.f + 8.f + 4.f));
  Rng rng(test_seed(5), 0);
  const int n = 60000;
  std::array<int, 6> count{};
  for (int i = 0; i < n; ++i) {
    const ShapeSample s = scene.sample_area(id, {rng.uniform(), rng.uniform()});
    EXPECT_FLOAT_EQ(s.pdf_area, 1.f / area);
    int face = -1;
    for (int a = 0; a < 3; ++a) {
      if (s.n[a] != 0.f) face = 2 * a + (s.n[a] > 0.f ? 1 : 0);
      EXPECT_GE(s.p[a], box.lo[a]);
      EXPECT_LE(s.p[a], box.hi[a]);
    }
    ASSERT_GE(face, 0);
    EXPECT_EQ(s.p[face / 2], face % 2 ? box.hi[face / 2] : box.lo[face / 2]);
    ++count[face];
  }
  const float face_area[3] = {8.f, 4.f, 2.f};  // faces normal to x, y, z
  for (int f = 0; f < 6; ++f) {
    const double p = face_area[f / 2] / area, sd = std::sqrt(n * p * (1 - p));
    EXPECT_NEAR(count[f], n * p, 4.0 * sd) << "face " << f;
  }
}

TEST(GeometryScene, AnalyticBoxRejectsEmptyOrNonFiniteBoxes) {
  GeometryScene scene;
  EXPECT_THROW(scene.add_box({{0, 0, 0}, {1, 0, 1}}), std::invalid_argument);
  EXPECT_THROW(scene.add_box({{0, 0, 0}, {1, std::nanf(""), 1}}), std::invalid_argument);
}

TEST(GeometryScene, SurfacePatchReproducesHits) {
  // The patch under a hit holds the hit point on its plane and interpolates the
  // hit's shading normal (barycentrics of the point); box faces are their plane
  // with the face normal; spheres have no patch.
  GeometryScene scene;
  const int sphere_mesh = scene.add_mesh(make_uv_sphere(Vec3(0.f), 1.f, 12, 24));
  const int box = scene.add_box(Bounds3{Vec3(2.f, -1.f, -1.f), Vec3(3.f, 1.f, 1.f)});
  const int sphere = scene.add_sphere(Vec3(-4.f, 0.f, 0.f), 1.f);
  scene.commit();
  EXPECT_FALSE(scene.surface_patch(sphere, 0));
  Rng rng(test_seed(3), 0);
  for (int i = 0; i < 200; ++i) {
    const Vec3 d = normalize(Vec3(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f));
    const auto hit = scene.intersect(Ray{Vec3(0.f), d}, 1.5f);
    ASSERT_TRUE(hit);
    ASSERT_EQ(hit->shape_id, sphere_mesh);
    const auto patch = scene.surface_patch(hit->shape_id, hit->prim_id);
    ASSERT_TRUE(patch);
    expect_near(patch->ng, hit->ng, 1e-5f);
    const Vec3 e1 = patch->p[1] - patch->p[0], e2 = patch->p[2] - patch->p[0], r = hit->p - patch->p[0];
    EXPECT_NEAR(dot(r, patch->ng), 0.f, 1e-5f);
    const float e11 = dot(e1, e1), e12 = dot(e1, e2), e22 = dot(e2, e2), det = e11 * e22 - e12 * e12;
    const float b1 = (e22 * dot(r, e1) - e12 * dot(r, e2)) / det, b2 = (e11 * dot(r, e2) - e12 * dot(r, e1)) / det;
    const Vec3 n = normalize((1.f - b1 - b2) * patch->n[0] + b1 * patch->n[1] + b2 * patch->n[2]);
    expect_near(n, hit->ns, 1e-4f);
    EXPECT_FALSE(scene.flat_face(hit->shape_id, hit->prim_id));
  }
  const auto hit = scene.intersect(Ray{Vec3(1.5f, 0.2f, 0.3f), Vec3(1.f, 0.f, 0.f)}, 10.f);
  ASSERT_TRUE(hit);
  ASSERT_EQ(hit->shape_id, box);
  const auto patch = scene.surface_patch(box, hit->prim_id);
  ASSERT_TRUE(patch);
  expect_near(patch->ng, Vec3(-1.f, 0.f, 0.f), 0.f);
  for (const Vec3& p : patch->p) EXPECT_EQ(p.x, 2.f);
  for (const Vec3& n : patch->n) expect_near(n, patch->ng, 0.f);
  EXPECT_TRUE(scene.flat_face(box, hit->prim_id));
}
