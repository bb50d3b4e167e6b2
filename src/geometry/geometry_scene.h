#pragma once
// All surfaces of a scene in one Embree BVH. Shapes are triangle meshes (kept
// in world space for sampling and shading data) and exact analytic spheres.
// Axis-aligned boxes (the implicit bounds of grid media) stay outside the BVH:
// a slab test costs a tenth of an Embree query, and a scene that holds only
// such boxes (the cloud benchmark) never calls Embree.
// Embree stays behind a pimpl: no other folder includes <embree3/rtcore.h>.
#include <array>
#include <memory>
#include <optional>

#include "core/sampling.h"
#include "core/transform.h"
#include "core/vec.h"
#include "geometry/mesh.h"

namespace chlorovdb {

struct SurfaceHit {
  float t = 0;   // ray parameter of the hit (metres when the ray direction is unit)
  Vec3 p;        // world-space point, metres
  Vec3 ng;       // unit geometric normal as stored (CCW-outward), NOT flipped toward the ray,
                 // so dot(ray.d, ng) > 0 means the ray leaves a closed mesh
  Vec3 ns;       // unit shading normal (interpolated; = ng without normals), same side as ng
  Point2 uv;     // mesh uvs if present, else barycentrics; spheres: (phi / 2pi, theta / pi);
                 // boxes: the face's other two coordinates in [0, 1], in axis order
  int shape_id = -1, prim_id = -1;  // boxes: prim_id = 2 axis + (1 on the max face)
  float p_error = 0;  // bound on |p - exact surface point| per axis, metres (drives spawn offsets)
};

// The plane patch a hit lies on, for solvers that move a point over a surface
// (manifold next-event estimation): a triangle's corners and vertex shading
// normals. Points p[0] + b1 (p[1] - p[0]) + b2 (p[2] - p[0]) continue the plane
// beyond the edges and the shading normal interpolates the same way
// (normalize(b0 n[0] + b1 n[1] + b2 n[2]), turned to ng's side, as in a hit).
// Box faces: three corners of the face, its normal at each.
struct SurfacePatch {
  std::array<Vec3, 3> p, n;
  Vec3 ng;  // unit, CCW-outward
};

struct ShapeSample {
  Vec3 p;          // world-space point on the shape, metres
  Vec3 n;          // unit geometric normal there (the side area lights emit to)
  float pdf_area;  // 1/m², uniform by area: 1 / area(shape)
};

class GeometryScene {
 public:
  GeometryScene();  // Embree starts with the first mesh or sphere (std::runtime_error if it cannot)
  ~GeometryScene();
  GeometryScene(GeometryScene&&) noexcept;
  GeometryScene& operator=(GeometryScene&&) noexcept;
  GeometryScene(const GeometryScene&) = delete;
  GeometryScene& operator=(const GeometryScene&) = delete;

  // Shape ids are dense, 0..n-1 in insertion order. Mesh triangles must not be
  // degenerate (load_mesh / drop_degenerate_triangles guarantee it).
  int add_mesh(TriangleMesh mesh, const Transform& world_from_object = {});
  int add_sphere(Vec3 center, float radius);
  // An axis-aligned box in world space, normals outward (as make_box's mesh).
  int add_box(const Bounds3& box);
  // Builds the BVH; call after the last add and before any query.
  void commit();

  // Closest hit with t in (0, t_max]. Thread-safe after commit().
  std::optional<SurfaceHit> intersect(const Ray& ray, float t_max) const;
  // Any hit with t in (0, t_max]. Thread-safe after commit().
  bool occluded(const Ray& ray, float t_max) const;

  // True when the surface around a hit on (shape_id, prim_id) is a plane with
  // the face's own normal for shading: box faces, and mesh triangles without
  // shading normals or whose three vertex normals equal the face normal.
  // Spheres and smooth-shaded triangles are not.
  bool flat_face(int shape_id, int prim_id) const;
  // The patch of (shape_id, prim_id); nullopt for spheres (not piecewise planar).
  std::optional<SurfacePatch> surface_patch(int shape_id, int prim_id) const;

  ShapeSample sample_area(int shape_id, Point2 u) const;
  float area(int shape_id) const;  // m²
  int shape_count() const;
  Bounds3 bounds() const;

  // A ray leaving `hit` along `dir` (kept as given) from an origin lifted off the
  // surface by the hit's error bound (pbrt-v4's offset), so it cannot re-hit
  // the surface it starts on, even far from the world origin.
  Ray spawn_ray(const SurfaceHit& hit, const Vec3& dir) const;
  // A shadow ray toward p_target with unit direction; *t_max (metres) stops
  // short of the target so a surface there is not reported as occluding.
  Ray spawn_ray_to(const SurfaceHit& hit, const Vec3& p_target, float* t_max) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace chlorovdb
